// TV-LQR: backward Riccati, feedforward and cost-to-go by CVODES BDF whose Newton systems
// are solved by exact Lyapunov solves for a frozen closed loop (see the header for why).
#include "freeflex/control/tvlqr.hpp"

#include <cvodes/cvodes.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_spgmr.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include "freeflex/control/lyapunov.hpp"
#include "sim/fast_nvector.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

static_assert(sizeof(sunrealtype) == sizeof(double), "freeflex needs SUNDIALS built with double precision");

std::string fmt(double v) { return util::format_number(v, 10); }

/// The state stores the upper triangle of the symmetric P̂ column by column, then ŝ, then ĉ.
int tri_size(int n) { return n * (n + 1) / 2; }
void unpack(const double* y, int n, Eigen::MatrixXd& P) {
  P.resize(n, n);
  for (int j = 0, k = 0; j < n; ++j)
    for (int i = 0; i <= j; ++i, ++k) P(i, j) = P(j, i) = y[k];
}
void pack(const Eigen::MatrixXd& F, double* out) {
  const int n = static_cast<int>(F.rows());
  for (int j = 0, k = 0; j < n; ++j)
    for (int i = 0; i <= j; ++i, ++k) out[k] = i == j ? F(i, i) : 0.5 * (F(i, j) + F(j, i));
}

/// Everything the CVODES callbacks need; no exception leaves a callback.
struct RiccatiData {
  const LtvSystem* sys = nullptr;
  double tf = 0.0;
  int n = 0, m = 0;
  double sigma = 1.0;
  Eigen::MatrixXd Qs;                // Q / σ
  Eigen::LLT<Eigen::MatrixXd> Rllt;  // R
  double piece_mid_t = 0.0;

  // model cache: CVODE evaluates many times at the same t (Newton iterations, jtimes)
  bool cached = false;
  double cache_t = 0.0, cache_mid = 0.0;
  Eigen::MatrixXd A, B;
  Eigen::VectorXd g;
  Eigen::MatrixXd G;   // B L⁻ᵀ with R = L Lᵀ: S = B R⁻¹ Bᵀ = G Gᵀ
  Eigen::MatrixXd At;  // Aᵀ (for detail::small_gemm)

  Eigen::MatrixXd Acl_j;  // jtimes: closed loop and w = g − σ S ŝ
  Eigen::VectorXd w_j;
  // the frozen closed loop A_cl of the last setup: block-diagonalized when its eigenvector
  // basis is well conditioned (modal), else in real Schur form (lyap)
  ModalLyapunovSolver modal;
  LyapunovSolver lyap;
  double max_condition = 0.0;
  bool use_modal = false;
  Eigen::VectorXd w_p;
  bool have_pre = false;
  long setups = 0, modal_setups = 0;

  Eigen::MatrixXd PG, AtP, Z, Pf, F, Vf;  // scratch
  Eigen::VectorXd v, zs, rhs_s;

  bool failed = false;
  std::string error;
  std::string cvode_error;

  /// Factorizes the frozen closed loop for the Newton solves.
  void refresh_frozen(const Eigen::MatrixXd& Acl) {
    use_modal = max_condition > 0.0 && modal.factorize(Acl, max_condition);
    if (use_modal)
      ++modal_setups;
    else
      lyap.factorize(Acl);
    have_pre = true;
    ++setups;
  }

  void fail(const std::string& msg) {
    if (!failed) error = msg;
    failed = true;
  }

  bool eval(double t) {
    if (cached && t == cache_t && piece_mid_t == cache_mid) return true;
    sys->state_space(Instant{t, piece_mid_t}, A, B, g);
    if (A.rows() != n || A.cols() != n || B.rows() != n || B.cols() != m || g.size() != n) {
      fail("the model returned A " + std::to_string(A.rows()) + " x " + std::to_string(A.cols()) + ", B " +
           std::to_string(B.rows()) + " x " + std::to_string(B.cols()) + ", g " + std::to_string(g.size()) +
           "; expected n = " + std::to_string(n) + ", m = " + std::to_string(m));
      return false;
    }
    if (!A.allFinite() || !B.allFinite() || !g.allFinite()) {
      fail("the model is not finite at t = " + fmt(t));
      return false;
    }
    At = A.transpose();
    G.noalias() = B.transpose();  // Gᵀ = L⁻¹ Bᵀ
    Rllt.matrixL().solveInPlace(G);
    G.transposeInPlace();
    cached = true;
    cache_t = t;
    cache_mid = piece_mid_t;
    return true;
  }

  /// A_cl = A − σ B R⁻¹ Bᵀ P̂ and w = g − σ B R⁻¹ Bᵀ ŝ at state y.
  void closed_loop(const double* y, Eigen::MatrixXd& Acl, Eigen::VectorXd& w) {
    unpack(y, n, Pf);
    Eigen::Map<const Eigen::VectorXd> s(y + tri_size(n), n);
    PG.noalias() = Pf * G;
    Acl = A;
    Acl.noalias() -= sigma * G * PG.transpose();
    v.noalias() = G.transpose() * s;
    w = g;
    w.noalias() -= sigma * G * v;
  }
};

double tau_to_t(const RiccatiData& d, double tau) { return d.tf - tau; }

extern "C" int freeflex_riccati_rhs(sunrealtype tau, N_Vector yv, N_Vector ydv, void* ud) {
  auto* d = static_cast<RiccatiData*>(ud);
  if (d->failed) return -1;
  try {
    if (!d->eval(tau_to_t(*d, tau))) return -1;
    const int n = d->n;
    const double* y = N_VGetArrayPointer(yv);
    double* yd = N_VGetArrayPointer(ydv);
    const int nt = tri_size(n);
    unpack(y, n, d->Pf);
    const Eigen::MatrixXd& P = d->Pf;
    Eigen::Map<const Eigen::VectorXd> s(y + nt, n);
    Eigen::Map<Eigen::VectorXd> ds(yd + nt, n);
    // dP̂/dτ = Aᵀ P̂ + P̂ A − σ (P̂ G)(P̂ G)ᵀ + Q/σ, packed from its upper triangle (each
    // entry is computed symmetric: P̂ A = (Aᵀ P̂)ᵀ)
    d->PG.noalias() = P * d->G;
    d->AtP.resize(n, n);
    detail::small_gemm(n, d->At.data(), P.data(), d->AtP.data(), false);
    const double sg = d->sigma;
    const Eigen::MatrixXd &AtP = d->AtP, &PG = d->PG, &Qs = d->Qs;
    const int m = d->m;
    for (int j = 0, k = 0; j < n; ++j)
      for (int i = 0; i <= j; ++i, ++k) {
        double psp = 0.0;
        for (int l = 0; l < m; ++l) psp += PG(i, l) * PG(j, l);
        yd[k] = AtP(i, j) + AtP(j, i) - sg * psp + Qs(i, j);
      }
    // dŝ/dτ = (A − σ S P̂)ᵀ ŝ + P̂ g = Aᵀ ŝ − σ (P̂ G)(Gᵀ ŝ) + P̂ g ;  dĉ/dτ = 2 ŝᵀ g − σ |Gᵀ ŝ|²
    d->v.noalias() = d->G.transpose() * s;
    ds.noalias() = d->A.transpose() * s;
    ds.noalias() -= sg * PG * d->v;
    ds.noalias() += P * d->g;
    yd[nt + n] = 2.0 * s.dot(d->g) - sg * d->v.squaredNorm();
    return 0;
  } catch (const std::exception& e) {
    d->fail(std::string("Riccati right-hand side threw: ") + e.what());
  } catch (...) {
    d->fail("Riccati right-hand side threw an unknown exception");
  }
  return -1;
}

extern "C" int freeflex_riccati_jtsetup(sunrealtype tau, N_Vector yv, N_Vector, void* ud) {
  auto* d = static_cast<RiccatiData*>(ud);
  if (d->failed) return -1;
  try {
    if (!d->eval(tau_to_t(*d, tau))) return -1;
    d->closed_loop(N_VGetArrayPointer(yv), d->Acl_j, d->w_j);
    return 0;
  } catch (...) {
    d->fail("Jacobian setup threw");
  }
  return -1;
}

extern "C" int freeflex_riccati_jtimes(N_Vector vv, N_Vector Jvv, sunrealtype, N_Vector, N_Vector, void* ud,
                                       N_Vector) {
  auto* d = static_cast<RiccatiData*>(ud);
  try {
    const int n = d->n;
    const double* v = N_VGetArrayPointer(vv);
    double* Jv = N_VGetArrayPointer(Jvv);
    const int nt = tri_size(n);
    unpack(v, n, d->Vf);
    const Eigen::MatrixXd& V = d->Vf;
    Eigen::Map<const Eigen::VectorXd> vs(v + nt, n);
    Eigen::Map<Eigen::VectorXd> Jvs(Jv + nt, n);
    d->F.noalias() = d->Acl_j.transpose() * V;
    pack(d->F + d->F.transpose(), Jv);  // Aclᵀ V + V Acl for symmetric V
    Jvs.noalias() = d->Acl_j.transpose() * vs;
    Jvs.noalias() += V * d->w_j;
    Jv[nt + n] = 2.0 * d->w_j.dot(vs);
    return 0;
  } catch (...) {
    d->fail("Jacobian-vector product threw");
  }
  return -1;
}

extern "C" int freeflex_riccati_psetup(sunrealtype tau, N_Vector yv, N_Vector, sunbooleantype jok,
                                       sunbooleantype* jcur, sunrealtype, void* ud) {
  auto* d = static_cast<RiccatiData*>(ud);
  if (d->failed) return -1;
  try {
    if (jok && d->have_pre) {
      *jcur = SUNFALSE;
      return 0;
    }
    if (!d->eval(tau_to_t(*d, tau))) return -1;
    Eigen::MatrixXd Acl;
    d->closed_loop(N_VGetArrayPointer(yv), Acl, d->w_p);
    d->refresh_frozen(Acl);
    *jcur = SUNTRUE;
    return 0;
  } catch (const std::exception& e) {
    d->fail(std::string("preconditioner setup threw: ") + e.what());
  } catch (...) {
    d->fail("preconditioner setup threw");
  }
  return -1;
}

/// z = (I − γJ)⁻¹ r with J frozen at the last setup: Z − γ(A_clᵀ Z + Z A_cl) = R_P, then
/// the s and c rows (block lower triangular). Returns 0, or 1 (recoverable) if singular.
int frozen_newton_solve(RiccatiData* d, const double* r, double* z, double gamma) {
  const int n = d->n, nt = tri_size(n);
  unpack(r, n, d->Vf);
  d->Vf *= -1.0 / gamma;
  Eigen::Map<const Eigen::VectorXd> rs(r + nt, n);
  const bool ok_p =
      d->use_modal ? d->modal.solve_symmetric(d->Vf, -0.5 / gamma, d->Z) : d->lyap.solve(d->Vf, -0.5 / gamma, d->Z);
  if (!ok_p) return 1;
  // (A_clᵀ − I/γ) z_s = −(r_s + γ Z w)/γ
  d->rhs_s.noalias() = -d->Z * d->w_p;
  d->rhs_s.noalias() -= rs / gamma;
  const bool ok_s = d->use_modal ? d->modal.solve_transposed(d->rhs_s, -1.0 / gamma, d->zs)
                                 : d->lyap.solve_transposed(d->rhs_s, -1.0 / gamma, d->zs);
  if (!ok_s) return 1;
  const double zc = r[nt + n] + 2.0 * gamma * d->w_p.dot(d->zs);
  pack(d->Z, z);
  Eigen::Map<Eigen::VectorXd>(z + nt, n) = d->zs;
  z[nt + n] = zc;
  return 0;
}

extern "C" int freeflex_riccati_psolve(sunrealtype, N_Vector, N_Vector, N_Vector rv, N_Vector zv, sunrealtype gamma,
                                       sunrealtype, int, void* ud) {
  auto* d = static_cast<RiccatiData*>(ud);
  try {
    return frozen_newton_solve(d, N_VGetArrayPointer(rv), N_VGetArrayPointer(zv), gamma);
  } catch (...) {
    d->fail("preconditioner solve threw");
  }
  return -1;
}

/// The direct ("matrix-embedded") linear solver: CVODES hands over the Newton systems and
/// the frozen exact solve above answers them, without GMRES and Jacobian products. CVODES
/// 6.4 gives such a solver no setup call, so the solve refreshes the frozen closed loop
/// itself, as CVODE's dense path would refresh its Jacobian: at the first solve, after
/// kRefreshSteps steps, and after a nonlinear convergence failure. (CVODE's dense default
/// is 20 steps; the solve uses the current γ exactly, so only the drift of A_cl ages the
/// Newton matrix, and 50 changed the step and right-hand-side counts of the benchmark by
/// < 2% while saving 60% of the refreshes: ~6% of the time at NOA = 6, 12% at 20.)
constexpr long kRefreshSteps = 50;
struct DirectSolverContent {
  RiccatiData* d = nullptr;
  void* cvode_mem = nullptr;
  long steps_at_setup = -1000;
  long fails_at_setup = 0;
};

extern "C" SUNLinearSolver_Type freeflex_direct_gettype(SUNLinearSolver) { return SUNLINEARSOLVER_MATRIX_EMBEDDED; }

extern "C" int freeflex_direct_solve(SUNLinearSolver S, SUNMatrix, N_Vector x, N_Vector b, sunrealtype) {
  auto* c = static_cast<DirectSolverContent*>(S->content);
  RiccatiData* d = c->d;
  if (d->failed) return -1;
  try {
    long nst = 0, ncf = 0;
    CVodeGetNumSteps(c->cvode_mem, &nst);
    CVodeGetNumNonlinSolvConvFails(c->cvode_mem, &ncf);
    if (!d->have_pre || nst - c->steps_at_setup >= kRefreshSteps || nst < c->steps_at_setup || ncf != c->fails_at_setup) {
      sunrealtype tcur = 0.0, gamma = 0.0, rl1 = 0.0;
      N_Vector ypred = nullptr, yn = nullptr, fn = nullptr, zn1 = nullptr;
      void* ud = nullptr;
      if (CVodeGetNonlinearSystemData(c->cvode_mem, &tcur, &ypred, &yn, &fn, &gamma, &rl1, &zn1, &ud) != CV_SUCCESS)
        return -1;
      if (!d->eval(tau_to_t(*d, tcur))) return -1;
      Eigen::MatrixXd Acl;
      d->closed_loop(N_VGetArrayPointer(ypred), Acl, d->w_p);
      d->refresh_frozen(Acl);
      c->steps_at_setup = nst;
      c->fails_at_setup = ncf;
    }
    sunrealtype gamma = 0.0;
    if (CVodeGetCurrentGamma(c->cvode_mem, &gamma) != CV_SUCCESS) return -1;
    return frozen_newton_solve(d, N_VGetArrayPointer(b), N_VGetArrayPointer(x), gamma) == 0 ? SUNLS_SUCCESS
                                                                                           : SUNLS_PSOLVE_FAIL_REC;
  } catch (...) {
    d->fail("direct linear solve threw");
  }
  return -1;
}

extern "C" int freeflex_direct_free(SUNLinearSolver S) {
  if (!S) return SUNLS_SUCCESS;
  S->content = nullptr;  // owned by solve_tvlqr
  SUNLinSolFreeEmpty(S);
  return SUNLS_SUCCESS;
}

extern "C" void freeflex_riccati_err(int code, const char* module, const char* function, char* msg, void* ud) {
  if (code >= 0) return;
  auto* d = static_cast<RiccatiData*>(ud);
  try {
    d->cvode_error = std::string(module ? module : "CVODES") + "::" + (function ? function : "?") + ": " +
                     (msg ? msg : "");
  } catch (...) {
  }
}

struct Cvodes {
  SUNContext ctx = nullptr;
  N_Vector y = nullptr;
  void* mem = nullptr;
  SUNLinearSolver LS = nullptr;
  Cvodes() = default;
  Cvodes(const Cvodes&) = delete;
  Cvodes& operator=(const Cvodes&) = delete;
  ~Cvodes() {
    if (mem) CVodeFree(&mem);
    if (LS) SUNLinSolFree(LS);
    if (y) N_VDestroy(y);
    if (ctx) SUNContext_Free(&ctx);
  }
};

void setup_ok(int flag, const char* call) {
  if (flag != CV_SUCCESS && flag != SUNLS_SUCCESS)
    throw std::runtime_error(std::string("solve_tvlqr: ") + call + " failed with flag " + std::to_string(flag));
}

std::string flag_name(int flag) {
  char* s = CVodeGetReturnFlagName(flag);
  if (!s) return "flag " + std::to_string(flag);
  std::string out(s);
  std::free(s);
  return out;
}

void validate(const LtvSystem& sys, const TvlqrOptions& o) {
  const std::string w = "tvlqr";
  auto fail = [&](const std::string& what) { throw std::invalid_argument(w + ": " + what); };
  if (sys.state_size < 1) fail("the system must have state_size >= 1, got " + std::to_string(sys.state_size));
  if (sys.input_size < 1) fail("the system must have at least one input, got " + std::to_string(sys.input_size));
  if (!sys.state_space) fail("the system's state_space function is empty");
  if (!std::isfinite(o.t0) || !std::isfinite(o.tf)) fail("t0 and tf must be finite");
  if (!(o.tf > o.t0)) fail("tf = " + fmt(o.tf) + " must be > t0 = " + fmt(o.t0));
  if (!(o.grid_step_s > 0.0) || !std::isfinite(o.grid_step_s))
    fail("grid_step_s = " + fmt(o.grid_step_s) + ", must be finite and > 0");
  if (!(o.rtol > 0.0) || !(o.atol > 0.0)) fail("rtol and atol must be > 0, got " + fmt(o.rtol) + ", " + fmt(o.atol));
  if (o.max_steps <= 0) fail("max_steps must be > 0");
  check_positive_semidefinite(o.Q, sys.state_size, "Q", w);
  check_positive_definite(o.R, sys.input_size, "R", w);
  if (o.Qf) check_positive_semidefinite(*o.Qf, sys.state_size, "Qf", w);
  for (double b : o.breakpoints)
    if (!std::isfinite(b)) fail("breakpoints must be finite");
}

}  // namespace

LtvSystem ltv_system(const FirstOrderModel& model) {
  LtvSystem s;
  s.state_size = model.state_size();
  s.input_size = model.input_size();
  s.state_space = [&model](const Instant& at, Eigen::MatrixXd& A, Eigen::MatrixXd& B, Eigen::VectorXd& g) {
    model.state_space(at, A, B, g);
  };
  s.breakpoints = model.nominal().breakpoints();
  return s;
}

TvlqrResult solve_tvlqr(const FirstOrderModel& model, const TvlqrOptions& options) {
  const RigidTrajectory& nom = model.nominal();
  const double span = std::max({1.0, std::abs(nom.t_begin()), std::abs(nom.t_end())});
  if (options.t0 < nom.t_begin() - 1e-12 * span)
    throw std::invalid_argument("tvlqr: t0 = " + fmt(options.t0) + " s is before the nominal motion begins (" +
                                fmt(nom.t_begin()) + " s)");
  if (options.tf < nom.t_end() - 1e-12 * span)
    throw std::invalid_argument("tvlqr: tf = " + fmt(options.tf) + " s ends before the nominal maneuver does (" +
                                fmt(nom.t_end()) + " s): the horizon must cover the maneuver");
  if (model.input_size() < 1)
    throw std::invalid_argument("tvlqr: the first-order model has no inputs (actuators); expected at least one");
  return solve_tvlqr(ltv_system(model), options);
}

TvlqrResult solve_tvlqr(const LtvSystem& sys, const TvlqrOptions& o) {
  validate(sys, o);
  const auto clock0 = std::chrono::steady_clock::now();
  const int n = sys.state_size, m = sys.input_size;
  TvlqrResult res;

  // Pieces [bounds_k, bounds_k+1] and the output grid (every bound is a grid time).
  const double span = o.tf - o.t0, merge = 1e-10 * span;
  std::vector<double> bounds{o.t0};
  {
    std::vector<double> b;
    for (double x : sys.breakpoints)
      if (x > o.t0 + merge && x < o.tf - merge) b.push_back(x);
    for (double x : o.breakpoints)
      if (x > o.t0 + merge && x < o.tf - merge) b.push_back(x);
    std::sort(b.begin(), b.end());
    for (double x : b)
      if (x - bounds.back() > merge) bounds.push_back(x);
    bounds.push_back(o.tf);
  }
  std::vector<double> grid = bounds;
  const long cells = std::lround(std::ceil(span / o.grid_step_s - 1e-9));
  for (long i = 1; i < cells; ++i) grid.push_back(o.t0 + i * o.grid_step_s);
  std::sort(grid.begin(), grid.end());
  {
    std::vector<double> g2;
    for (double x : grid) {
      const bool is_bound = std::binary_search(bounds.begin(), bounds.end(), x);
      if (!g2.empty() && x - g2.back() <= merge) {
        if (is_bound) g2.back() = x;  // keep the breakpoint itself
        continue;
      }
      g2.push_back(x);
    }
    grid = g2;
  }
  const int G = static_cast<int>(grid.size());

  RiccatiData d;
  d.sys = &sys;
  d.tf = o.tf;
  d.n = n;
  d.m = m;
  d.Rllt.compute(0.5 * (o.R + o.R.transpose()));
  d.max_condition = o.modal_max_condition;
  d.piece_mid_t = 0.5 * (bounds[bounds.size() - 2] + bounds.back());

  // Terminal weight.
  if (o.Qf) {
    res.Qf = 0.5 * (*o.Qf + o.Qf->transpose());
  } else {
    if (!d.eval(o.tf)) {
      res.status = TvlqrResult::Status::TerminalCareFailed;
      res.message = "terminal CARE: " + d.error;
      return res;
    }
    CareOptions co;
    co.restrict_to_controllable = true;
    CareResult care = solve_care(d.A, d.B, o.Q, o.R, co);
    if (!care.ok()) {
      res.status = TvlqrResult::Status::TerminalCareFailed;
      res.message = "terminal CARE at tf = " + fmt(o.tf) + " s failed: " + care.message;
      res.terminal_care = std::move(care);
      return res;
    }
    res.Qf = care.P;
    res.terminal_care = std::move(care);
  }
  d.sigma = std::max(res.Qf.cwiseAbs().maxCoeff(), o.Q.cwiseAbs().maxCoeff());
  if (!(d.sigma > 0.0)) d.sigma = 1.0;
  d.Qs = 0.5 * (o.Q + o.Q.transpose()) / d.sigma;

  res.t = grid;
  res.K.assign(G, Eigen::MatrixXd());
  res.feedforward.setZero(G, m);
  if (o.store_riccati) res.P.assign(G, Eigen::MatrixXd());

  const int nt = tri_size(n), dim = nt + n + 1;
  Cvodes cv;
  if (SUNContext_Create(nullptr, &cv.ctx) != 0) throw std::runtime_error("solve_tvlqr: SUNContext_Create failed");
  cv.y = N_VNew_Serial(dim, cv.ctx);
  if (!cv.y) throw std::runtime_error("solve_tvlqr: N_VNew_Serial failed");
  use_compiled_vector_kernels(cv.y);  // clones made by CVODES inherit them
  double* y = N_VGetArrayPointer(cv.y);
  Eigen::Map<Eigen::VectorXd>(y, dim).setZero();
  pack(res.Qf / d.sigma, y);

  Eigen::MatrixXd Psym, Krec;  // scratch of record()
  Eigen::VectorXd ffrec;
  auto record = [&](int idx) -> bool {
    const double t = grid[idx];
    if (!d.eval(t)) return false;
    unpack(y, n, Psym);
    Psym *= d.sigma;
    Eigen::Map<const Eigen::VectorXd> sh(y + nt, n);
    Krec.noalias() = d.B.transpose() * Psym;
    d.Rllt.solveInPlace(Krec);
    res.K[idx] = Krec;
    ffrec.noalias() = d.B.transpose() * sh;
    d.Rllt.solveInPlace(ffrec);
    res.feedforward.row(idx) = -d.sigma * ffrec.transpose();
    if (o.store_riccati) res.P[idx] = Psym;
    if (idx == 0) {
      res.P0 = Psym;
      res.s0 = d.sigma * sh;
      res.c0 = d.sigma * y[nt + n];
    }
    return true;
  };
  auto finish = [&](TvlqrResult::Status st, std::string msg) {
    res.status = st;
    res.message = std::move(msg);
    res.preconditioner_setups = d.setups;
    res.modal_setups = d.modal_setups;
    res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
    return res;
  };

  cv.mem = CVodeCreate(CV_BDF, cv.ctx);
  if (!cv.mem) throw std::runtime_error("solve_tvlqr: CVodeCreate failed");
  setup_ok(CVodeSetErrHandlerFn(cv.mem, freeflex_riccati_err, &d), "CVodeSetErrHandlerFn");
  setup_ok(CVodeInit(cv.mem, freeflex_riccati_rhs, 0.0, cv.y), "CVodeInit");
  setup_ok(CVodeSStolerances(cv.mem, o.rtol, o.atol), "CVodeSStolerances");
  setup_ok(CVodeSetUserData(cv.mem, &d), "CVodeSetUserData");
  setup_ok(CVodeSetMaxNumSteps(cv.mem, o.max_steps), "CVodeSetMaxNumSteps");
  DirectSolverContent direct{&d, cv.mem};
  if (o.newton_solver == TvlqrOptions::NewtonSolver::Lyapunov) {
    cv.LS = SUNLinSolNewEmpty(cv.ctx);
    if (!cv.LS) throw std::runtime_error("solve_tvlqr: SUNLinSolNewEmpty failed");
    cv.LS->content = &direct;
    cv.LS->ops->gettype = freeflex_direct_gettype;
    cv.LS->ops->solve = freeflex_direct_solve;
    cv.LS->ops->free = freeflex_direct_free;
    setup_ok(CVodeSetLinearSolver(cv.mem, cv.LS, nullptr), "CVodeSetLinearSolver");
  } else {
    cv.LS = SUNLinSol_SPGMR(cv.y, SUN_PREC_LEFT, 10, cv.ctx);
    if (!cv.LS) throw std::runtime_error("solve_tvlqr: SUNLinSol_SPGMR failed");
    setup_ok(CVodeSetLinearSolver(cv.mem, cv.LS, nullptr), "CVodeSetLinearSolver");
    setup_ok(CVodeSetPreconditioner(cv.mem, freeflex_riccati_psetup, freeflex_riccati_psolve),
             "CVodeSetPreconditioner");
    setup_ok(CVodeSetJacTimes(cv.mem, freeflex_riccati_jtsetup, freeflex_riccati_jtimes), "CVodeSetJacTimes");
  }

  auto add_stats = [&]() {
    long nst = 0, nfe = 0, nli = 0;
    CVodeGetNumSteps(cv.mem, &nst);
    CVodeGetNumRhsEvals(cv.mem, &nfe);
    CVodeGetNumLinIters(cv.mem, &nli);
    res.steps += nst;
    res.rhs_evaluations += nfe;
    res.linear_iterations += nli;
  };

  int idx = G - 1;
  if (!record(idx)) return finish(TvlqrResult::Status::IntegrationFailed, d.error);
  --idx;
  const int pieces = static_cast<int>(bounds.size()) - 1;
  for (int p = pieces - 1; p >= 0; --p) {
    const double a_t = bounds[p], b_t = bounds[p + 1];
    const double tau_a = o.tf - b_t, tau_b = o.tf - a_t;
    d.piece_mid_t = 0.5 * (a_t + b_t);
    d.cached = false;
    d.have_pre = false;  // the model may jump at a breakpoint: refresh the frozen closed loop
    if (p != pieces - 1) setup_ok(CVodeReInit(cv.mem, tau_a, cv.y), "CVodeReInit");
    setup_ok(CVodeSetStopTime(cv.mem, tau_b), "CVodeSetStopTime");
    while (idx >= 0 && grid[idx] >= a_t) {
      const double tau_out = (grid[idx] == a_t) ? tau_b : o.tf - grid[idx];
      sunrealtype tret = tau_out;
      const int flag = CVode(cv.mem, tau_out, cv.y, &tret, CV_NORMAL);
      if (flag < 0) {
        add_stats();
        std::string msg = "CVODES failed at t = " + fmt(o.tf - tret) + " s: " + flag_name(flag);
        // CVODES's own message counts the backward time τ = tf - t.
        const std::string why = !d.error.empty() ? d.error : d.cvode_error.empty() ? "" : d.cvode_error + " [τ = tf - t]";
        if (!why.empty()) msg += " (" + why + ")";
        return finish(TvlqrResult::Status::IntegrationFailed, msg);
      }
      if (!Eigen::Map<const Eigen::VectorXd>(y, dim).allFinite()) {
        add_stats();
        return finish(TvlqrResult::Status::IntegrationFailed,
                      "the Riccati solution became non-finite at t = " + fmt(o.tf - tret) + " s");
      }
      if (!record(idx)) return finish(TvlqrResult::Status::IntegrationFailed, d.error);
      if (o.progress) o.progress(o.tf - grid[idx]);
      --idx;
    }
    add_stats();
  }
  return finish(TvlqrResult::Status::Solved, "solved");
}

namespace {
/// Index i with t[i] <= time < t[i+1] (clamped) and the weight of t[i+1].
std::pair<int, double> locate(const std::vector<double>& t, double time) {
  if (t.size() < 2 || time <= t.front()) return {0, 0.0};
  if (time >= t.back()) return {static_cast<int>(t.size()) - 2, 1.0};
  const auto it = std::upper_bound(t.begin(), t.end(), time);
  const int i = static_cast<int>(it - t.begin()) - 1;
  return {i, (time - t[i]) / (t[i + 1] - t[i])};
}
}  // namespace

Eigen::MatrixXd TvlqrResult::gain(double time) const {
  if (K.empty()) throw std::logic_error("TvlqrResult::gain: no gains stored (the solve failed)");
  if (K.size() == 1) return K.front();
  const auto [i, w] = locate(t, time);
  return (1.0 - w) * K[i] + w * K[i + 1];
}

Eigen::VectorXd TvlqrResult::feedforward_at(double time) const {
  if (feedforward.rows() == 0) throw std::logic_error("TvlqrResult::feedforward_at: nothing stored (the solve failed)");
  if (feedforward.rows() == 1) return feedforward.row(0).transpose();
  const auto [i, w] = locate(t, time);
  return ((1.0 - w) * feedforward.row(i) + w * feedforward.row(i + 1)).transpose();
}

Eigen::VectorXd TvlqrResult::control(double time, const Eigen::Ref<const Eigen::VectorXd>& x1) const {
  const Eigen::MatrixXd Kt = gain(time);
  if (x1.size() != Kt.cols())
    throw std::invalid_argument("TvlqrResult::control: expected x1 of size " + std::to_string(Kt.cols()) + ", got " +
                                std::to_string(x1.size()));
  return -Kt * x1 + feedforward_at(time);
}

double TvlqrResult::predicted_cost(const Eigen::Ref<const Eigen::VectorXd>& x1) const {
  if (x1.size() != P0.rows())
    throw std::invalid_argument("TvlqrResult::predicted_cost: expected x1 of size " + std::to_string(P0.rows()) +
                                ", got " + std::to_string(x1.size()));
  return x1.dot(P0 * x1) + 2.0 * s0.dot(x1) + c0;
}

}  // namespace freeflex

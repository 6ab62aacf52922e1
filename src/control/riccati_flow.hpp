#pragma once
// The backward Riccati flow of the TV-LQR as CVODES sees it (control/tvlqr.hpp explains
// the method): the packed state, the data every callback shares, the right-hand side,
// the Jacobian products and the Newton solves for a frozen closed loop, and the
// matrix-embedded linear solver that answers CVODES's Newton systems with them. Private
// to src/; control/tvlqr.cpp drives the sweep.
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_nvector.h>

#include <string>

#include <Eigen/Dense>

#include "control/lyapunov_solvers.hpp"
#include "freeflex/control/tvlqr.hpp"
#include "util/finite.hpp"
#include "util/format.hpp"

namespace freeflex::detail {

/// Where the sweep gets A(t), B(t), g(t): a user's LtvSystem, or a FirstOrderModel and
/// its workspace directly (no allocation per evaluation).
class LtvEvaluator {
 public:
  virtual ~LtvEvaluator() = default;
  /// The model at `at`; the reference stays valid until the next call.
  virtual const StateSpace& eval(const Instant& at) = 0;
};

/// The state stores the upper triangle of the symmetric P̂ column by column, then ŝ, then ĉ.
inline int tri_size(int n) { return n * (n + 1) / 2; }
inline void unpack(const double* y, int n, Eigen::MatrixXd& P) {
  P.resize(n, n);
  for (int j = 0, k = 0; j < n; ++j)
    for (int i = 0; i <= j; ++i, ++k) P(i, j) = P(j, i) = y[k];
}
inline void pack(const Eigen::MatrixXd& F, double* out) {
  const int n = static_cast<int>(F.rows());
  for (int j = 0, k = 0; j < n; ++j)
    for (int i = 0; i <= j; ++i, ++k) out[k] = i == j ? F(i, i) : 0.5 * (F(i, j) + F(j, i));
}

/// Everything the CVODES callbacks need; no exception leaves a callback.
struct RiccatiData {
  LtvEvaluator* model = nullptr;
  double tf = 0.0;
  int n = 0, m = 0;
  double sigma = 1.0;
  Eigen::MatrixXd Qs;                // Q / σ
  Eigen::LLT<Eigen::MatrixXd> Rllt;  // R
  double piece_mid_t = 0.0;

  // model cache: CVODE evaluates many times at the same t (Newton iterations, jtimes)
  bool cached = false;
  double cache_t = 0.0, cache_mid = 0.0;
  const StateSpace* ss = nullptr;  // the model's A, B, g at cache_t
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

  const Eigen::MatrixXd& A() const { return ss->A; }
  const Eigen::MatrixXd& B() const { return ss->B; }
  const Eigen::VectorXd& g() const { return ss->g; }

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
    ss = &model->eval(Instant{t, piece_mid_t});
    const Eigen::MatrixXd &A = ss->A, &B = ss->B;
    const Eigen::VectorXd& g = ss->g;
    if (A.rows() != n || A.cols() != n || B.rows() != n || B.cols() != m || g.size() != n) {
      fail("the model returned A " + std::to_string(A.rows()) + " x " + std::to_string(A.cols()) + ", B " +
           std::to_string(B.rows()) + " x " + std::to_string(B.cols()) + ", g " + std::to_string(g.size()) +
           "; expected n = " + std::to_string(n) + ", m = " + std::to_string(m));
      return false;
    }
    if (!util::all_finite(A) || !util::all_finite(B) || !util::all_finite(g)) {
      fail("the model is not finite at t = " + util::format_number(t, 10));
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
    Acl = A();
    Acl.noalias() -= sigma * G * PG.transpose();
    v.noalias() = G.transpose() * s;
    w = g();
    w.noalias() -= sigma * G * v;
  }
};

inline double tau_to_t(const RiccatiData& d, double tau) { return d.tf - tau; }

/// The matrix-embedded linear solver: CVODES hands over the Newton systems and the frozen
/// exact solve answers them (see riccati_flow.cpp). `content` must outlive the solver.
struct DirectSolverContent {
  RiccatiData* d = nullptr;
  void* cvode_mem = nullptr;
  long steps_at_setup = -1000;
  long fails_at_setup = 0;
};
SUNLinearSolver make_direct_solver(SUNContext ctx, DirectSolverContent* content);

extern "C" {
int freeflex_riccati_rhs(sunrealtype tau, N_Vector yv, N_Vector ydv, void* ud);
int freeflex_riccati_jtsetup(sunrealtype tau, N_Vector yv, N_Vector, void* ud);
int freeflex_riccati_jtimes(N_Vector vv, N_Vector Jvv, sunrealtype, N_Vector, N_Vector, void* ud, N_Vector);
int freeflex_riccati_psetup(sunrealtype tau, N_Vector yv, N_Vector, sunbooleantype jok, sunbooleantype* jcur,
                            sunrealtype, void* ud);
int freeflex_riccati_psolve(sunrealtype, N_Vector, N_Vector, N_Vector rv, N_Vector zv, sunrealtype gamma, sunrealtype,
                            int, void* ud);
}

}  // namespace freeflex::detail

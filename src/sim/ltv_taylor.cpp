// Taylor-series integration of the first-order model (docs/theory.md section 8).
#include "sim/ltv_taylor.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include <unsupported/Eigen/MatrixFunctions>

#include "dynamics/planar.hpp"
#include "util/format.hpp"

namespace freeflex::detail {
namespace {

/// The Taylor steps make the series' last two terms this fraction of the error weights
/// (atol + rtol |y|): the global error then stays near rtol |y| over some thousand steps
/// (docs/benchmarks.md, the Taylor rows).
constexpr double kLocalError = 1e-3;
/// A step is at most this many times 1/‖A0‖ (about the period of the fastest mode over
/// 2π): the series' largest terms, e^(h‖A‖) / sqrt(2π h‖A‖) times the state, then cost at
/// most five digits to cancellation.
constexpr double kMaxStepNorm = 16.0;
/// Fewest terms of a step (a step's last two terms can vanish by symmetry before).
constexpr int kMinOrder = 8;
constexpr int kFixed = 6;  // 1, θ0', θ0'², θ0'', a_x, a_y; then u, u cos θ0, u sin θ0 of each command

/// A nominal motion frozen at one state (for evaluating the model at chosen θ0', θ0'', R0'').
class FrozenTrajectory : public RigidTrajectory {
 public:
  RigidState state;
  RigidState at(const Instant&) const override { return state; }
  double t_begin() const override { return -std::numeric_limits<double>::max(); }
  double t_end() const override { return std::numeric_limits<double>::max(); }
  std::vector<double> breakpoints() const override { return {}; }
};

/// Turns the R1 and R1' blocks of a state by C (x_b = C x or C x_b).
void turn(Eigen::Ref<Eigen::VectorXd> x, const Eigen::Matrix2d& C, int N) {
  for (int i : {0, N}) {
    const Eigen::Vector2d v = C * x.segment<2>(i);
    x.segment<2>(i) = v;
  }
}

}  // namespace

SparseEntries::SparseEntries(const Eigen::MatrixXd& A) {
  for (Eigen::Index r = 0; r < A.rows(); ++r)
    for (Eigen::Index c = 0; c < A.cols(); ++c)
      if (A(r, c) != 0.0) {
        row.push_back(static_cast<int>(r));
        col.push_back(static_cast<int>(c));
        val.push_back(A(r, c));
      }
  if (val.empty()) return;
  r0 = *std::min_element(row.begin(), row.end());
  c0 = *std::min_element(col.begin(), col.end());
  const int nr = *std::max_element(row.begin(), row.end()) - r0 + 1;
  const int nc = *std::max_element(col.begin(), col.end()) - c0 + 1;
  dense = nr * nc >= 16 && 10 * size() >= 3 * nr * nc;
  if (dense) {
    box.resize(nr, nc);
  } else if (A.rows() == A.cols() && A.rows() % 2 == 0) {
    const int h = static_cast<int>(A.rows()) / 2;
    int on_band = 0;
    for (int e = 0; e < size(); ++e) on_band += std::abs(col[e] - row[e]) == h;
    if (4 * on_band >= h) {  // worth two vector operations
      upper.setZero(h);
      lower.setZero(h);
    }
    for (int e = 0; e < size(); ++e)
      if (upper.size() == 0 || std::abs(col[e] - row[e]) != h) rest.push_back(e);
    for (int e : rest) {
      rest_row.push_back(row[static_cast<std::size_t>(e)]);
      rest_col.push_back(col[static_cast<std::size_t>(e)]);
    }
    rest_val.resize(rest.size());
  }
  refresh();
}

void SparseEntries::refresh() {
  if (dense) {
    box.setZero();
    for (int e = 0; e < size(); ++e) box(row[e] - r0, col[e] - c0) = val[e];
    return;
  }
  const int h = static_cast<int>(upper.size());
  if (h > 0)
    for (int e = 0; e < size(); ++e) {
      if (col[e] - row[e] == h) upper(row[e]) = val[e];
      if (row[e] - col[e] == h) lower(col[e]) = val[e];
    }
  for (std::size_t k = 0; k < rest.size(); ++k) rest_val[k] = val[static_cast<std::size_t>(rest[k])];
}

void LtvCoefficients::at(const Instant& when, Eigen::Ref<Eigen::VectorXd> c, double& theta0,
                         Eigen::VectorXd& u) const {
  const RigidState s = nominal->at(when);
  theta0 = s.pos(2);
  const double w = s.vel(2);
  const Eigen::Vector2d a = planar::rot(theta0).transpose() * s.acc.head<2>();
  c(0) = 1.0;
  c(1) = w;
  c(2) = w * w;
  c(3) = s.acc(2);
  c(4) = a(0);
  c(5) = a(1);
  if (u.size() > 0) {
    commands(when, u);
    const double co = std::cos(theta0), si = std::sin(theta0);
    for (Eigen::Index e = 0; e < u.size(); ++e) c.segment<3>(kFixed + 3 * e) << u(e), u(e) * co, u(e) * si;
  }
}

namespace {

/// The first-order model at a frozen nominal state, in the form's coordinates y:
/// S⁻¹ (Cᵀ A C − θ0' J) S and S⁻¹ Cᵀ g.
class FrozenModel {
 public:
  FrozenModel(const FlexibleBody& body, const LtvForm& form)
      : form_(form),
        u(Eigen::VectorXd::Zero(static_cast<Eigen::Index>(body.elements().size()))),
        model_(body, frozen_, [this](const Instant&, Eigen::Ref<Eigen::VectorXd> c) { c = u; }, {}),
        data_(model_.create_data()) {}
  void evaluate(double theta0, double w, double wd, const Eigen::Vector2d& Rdd) {
    const int N = form_.N;
    frozen_.state.pos = Eigen::Vector3d(0.0, 0.0, theta0);
    frozen_.state.vel = Eigen::Vector3d(0.0, 0.0, w);
    frozen_.state.acc = Eigen::Vector3d(Rdd(0), Rdd(1), wd);
    const StateSpace& ss = model_.state_space(data_, Instant::at(0.0));
    const Eigen::Matrix2d C = planar::rot(theta0);
    Ab_ = ss.A;
    gb_ = ss.g;
    for (int i : {0, N}) {
      Ab_.middleRows(i, 2) = C.transpose() * Ab_.middleRows(i, 2);
      Ab_.middleCols(i, 2) = Ab_.middleCols(i, 2) * C;
      Ab_(i, i + 1) += w;  // − θ0' J, J = [[0, -1], [1, 0]]
      Ab_(i + 1, i) -= w;
    }
    turn(gb_, C.transpose(), N);
    M.noalias() = form_.S_inv * Ab_ * form_.S;
    g.noalias() = form_.S_inv * gb_;
  }

 private:
  const LtvForm& form_;

 public:
  Eigen::VectorXd u;  ///< the commands
  Eigen::MatrixXd M;
  Eigen::VectorXd g;

 private:
  FrozenTrajectory frozen_;
  const FirstOrderModel model_;
  FirstOrderModel::Data data_;
  Eigen::MatrixXd Ab_;
  Eigen::VectorXd gb_;
};

}  // namespace

double ltv_form_misfit(const LtvForm& f, const FlexibleBody& body, double rate_scale, double accel_scale,
                       double command_scale) {
  FrozenModel fm(body, f);
  const int n = f.n, nb = static_cast<int>(f.A.size()), m = static_cast<int>(fm.u.size());
  const double sw = rate_scale > 0.0 ? rate_scale : 1.0, sa = accel_scale > 0.0 ? accel_scale : 1.0,
               su = command_scale > 0.0 ? command_scale : 1.0;
  std::mt19937 gen(8);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  Eigen::VectorXd c(nb);
  double misfit = 0.0;
  for (int trial = 0; trial < 4; ++trial) {
    const double th = 3.2 * U(gen), w = sw * U(gen), wd = sa * U(gen);
    const Eigen::Vector2d Rdd(sa * U(gen), sa * U(gen));
    for (int e = 0; e < m; ++e) fm.u(e) = su * U(gen);
    fm.evaluate(th, w, wd, Rdd);
    const Eigen::Vector2d a = planar::rot(th).transpose() * Rdd;
    c.head<kFixed>() << 1.0, w, w * w, wd, a(0), a(1);
    for (int e = 0; e < m; ++e) c.segment<3>(kFixed + 3 * e) << fm.u(e), fm.u(e) * std::cos(th), fm.u(e) * std::sin(th);
    Eigen::MatrixXd sumA = Eigen::MatrixXd::Zero(n, n), size = sumA;
    Eigen::VectorXd sumg = Eigen::VectorXd::Zero(n), gsize = sumg;
    for (int i = 0; i < nb; ++i) {
      if (f.A[i].size()) {
        sumA += c(i) * f.A[i];
        size += std::abs(c(i)) * f.A[i].cwiseAbs();
      }
      if (f.g[i].size()) {
        sumg += c(i) * f.g[i];
        gsize += std::abs(c(i)) * f.g[i].cwiseAbs();
      }
    }
    // The matrix against its largest entry: in y, entries that should vanish carry the
    // round-off of the modal transformation (~1e-12 of the largest at NOA 20), which turns
    // with θ0. The forcing row by row (it has no such entries), against the size of the
    // row's terms but not below 1e-4 of the largest (rows whose forcing is round-off).
    const double big = std::max(size.maxCoeff(), fm.M.cwiseAbs().maxCoeff());
    if (big > 0.0) misfit = std::max(misfit, (fm.M - sumA).cwiseAbs().maxCoeff() / big);
    const double floor_g = 1e-4 * std::max(gsize.maxCoeff(), fm.g.cwiseAbs().maxCoeff());
    for (int r = 0; r < n; ++r) {
      const double rg = std::max({gsize(r), std::abs(fm.g(r)), floor_g});
      if (rg > 0.0) misfit = std::max(misfit, std::abs(fm.g(r) - sumg(r)) / rg);
    }
  }
  return misfit;
}

LtvForm ltv_form(const FlexibleBody& body, double rate_scale, double accel_scale, double command_scale) {
  LtvForm f;
  const int N = body.dofs(), n = 2 * N, ne = body.n();
  const int m = static_cast<int>(body.elements().size());
  const int nb = kFixed + 3 * m;
  f.n = n;
  f.N = N;
  // y: rigid coordinates shifted by the rigid motion the deformation carries, q in the
  // rest modes, the rates divided by ω (the modal integration variables' scaling).
  const RestModes rm = rest_modes(body);
  f.omega = rm.omega2.cwiseSqrt();
  const Eigen::MatrixXd Phi_inv = rm.Phi.transpose() * rm.M_c;
  f.S = Eigen::MatrixXd::Identity(n, n);
  f.S_inv = f.S;
  f.S.block(3, 3, ne, ne) = rm.Phi;
  f.S.block(0, 3, 3, ne) = -rm.T * rm.Phi;
  f.S.block(N + 3, N + 3, ne, ne) = rm.Phi * f.omega.asDiagonal();
  f.S.block(N, N + 3, 3, ne) = -rm.T * rm.Phi * f.omega.asDiagonal();
  f.S_inv.block(3, 3, ne, ne) = Phi_inv;
  f.S_inv.block(0, 3, 3, ne) = rm.T;
  f.S_inv.block(N + 3, N + 3, ne, ne) = f.omega.cwiseInverse().asDiagonal() * Phi_inv;
  f.S_inv.block(N, N + 3, 3, ne) = rm.T;

  FrozenModel fm(body, f);
  const Eigen::Vector2d zero2 = Eigen::Vector2d::Zero();
  f.A.assign(nb, Eigen::MatrixXd());
  f.g.assign(nb, Eigen::VectorXd());
  fm.evaluate(0.0, 0.0, 0.0, zero2);
  const Eigen::MatrixXd M0 = fm.M;
  const Eigen::VectorXd g0 = fm.g;
  f.A[0] = M0;
  f.g[0] = g0;
  // θ0' enters to second order: central differences of a quadratic are exact to round-off.
  const double sw = rate_scale > 0.0 ? rate_scale : 1.0;
  fm.evaluate(0.0, sw, 0.0, zero2);
  const Eigen::MatrixXd Mp = fm.M;
  const Eigen::VectorXd gp = fm.g;
  fm.evaluate(0.0, -sw, 0.0, zero2);
  f.A[1] = (Mp - fm.M) / (2.0 * sw);
  f.g[1] = (gp - fm.g) / (2.0 * sw);
  f.A[2] = (Mp + fm.M - 2.0 * M0) / (2.0 * sw * sw);
  f.g[2] = (gp + fm.g - 2.0 * g0) / (2.0 * sw * sw);
  // θ0'' and a enter linearly.
  const double sa = accel_scale > 0.0 ? accel_scale : 1.0;
  fm.evaluate(0.0, 0.0, sa, zero2);
  f.A[3] = (fm.M - M0) / sa;
  f.g[3] = (fm.g - g0) / sa;
  for (int k = 0; k < 2; ++k) {
    Eigen::Vector2d a = zero2;
    a(k) = sa;
    fm.evaluate(0.0, 0.0, 0.0, a);
    f.A[4 + k] = (fm.M - M0) / sa;
    f.g[4 + k] = (fm.g - g0) / sa;
  }
  // A command enters linearly, in the body frame as u, u cos θ0 and u sin θ0 (a force
  // fixed in space turns against the body): its change at θ0 = 0, π/2 and π.
  const double su = command_scale > 0.0 ? command_scale : 1.0;
  const double quarter = 0.5 * M_PI;
  for (int e = 0; e < m; ++e) {
    Eigen::MatrixXd dM[3];
    Eigen::VectorXd dg[3];
    for (int k = 0; k < 3; ++k) {
      fm.u.setZero();
      fm.evaluate(k * quarter, 0.0, 0.0, zero2);
      const Eigen::MatrixXd Mr = fm.M;
      const Eigen::VectorXd gr = fm.g;
      fm.u(e) = su;
      fm.evaluate(k * quarter, 0.0, 0.0, zero2);
      dM[k] = (fm.M - Mr) / su;
      dg[k] = (fm.g - gr) / su;
    }
    const int i = kFixed + 3 * e;
    f.A[i] = 0.5 * (dM[0] + dM[2]);
    f.A[i + 1] = 0.5 * (dM[0] - dM[2]);
    f.A[i + 2] = dM[1] - f.A[i];
    f.g[i] = 0.5 * (dg[0] + dg[2]);
    f.g[i + 1] = 0.5 * (dg[0] - dg[2]);
    f.g[i + 2] = dg[1] - f.g[i];
    // of the three, those at round-off of the largest are not there (1e-9: round-off of
    // the modal transformation reaches 1e-11 at NOA 12; a term dropped wrongly would show
    // in the check below)
    double big = 0.0, gbig = 0.0;
    for (int k = 0; k < 3; ++k) {
      big = std::max(big, f.A[i + k].cwiseAbs().maxCoeff());
      gbig = std::max(gbig, f.g[i + k].cwiseAbs().maxCoeff());
    }
    for (int k = 0; k < 3; ++k) {
      if (f.A[i + k].cwiseAbs().maxCoeff() <= 1e-9 * big) f.A[i + k].setZero();
      if (f.g[i + k].cwiseAbs().maxCoeff() <= 1e-9 * gbig) f.g[i + k].setZero();
    }
  }
  fm.u.setZero();
  // Entries at round-off of a term's largest are differences of equal numbers: zero.
  for (int i = 0; i < nb; ++i) {
    const double big = f.A[i].cwiseAbs().maxCoeff();
    f.A[i] = (f.A[i].array().abs() > 1e-14 * big).select(f.A[i], 0.0);
    if (i > 0 && big == 0.0) f.A[i].resize(0, 0);
    const double gbig = f.g[i].cwiseAbs().maxCoeff();
    f.g[i] = (f.g[i].array().abs() > 1e-14 * gbig).select(f.g[i], 0.0);
    if (gbig == 0.0) f.g[i].resize(0);
  }
  f.misfit = ltv_form_misfit(f, body, sw, sa, su);
  if (!(f.misfit <= kMaxMisfit))
    f.unsupported = "the first-order model of this body is not linear in the nominal motion's rate squared, "
                    "its accelerations in the body frame and the commands (misfit " +
                    util::format_number(f.misfit, 3) + " of the terms' size, above " +
                    util::format_number(kMaxMisfit, 3) + ")";
  return f;
}

IntegrationResult integrate_ltv_taylor(const LtvForm& form, const LtvCoefficients& coefficients,
                                       const std::vector<double>& outs, const std::vector<double>& breakpoints,
                                       const IntegratorOptions& options, int order,
                                       const std::function<std::string(const Instant&, const Eigen::Ref<const Eigen::VectorXd>&)>&
                                           range_check) {
  const int n = form.n, N = form.N, nb = static_cast<int>(form.A.size());
  const int m = (nb - kFixed) / 3;
  validate(options);
  if (order < 2) throw std::invalid_argument("integrate_ltv_taylor: order = " + std::to_string(order) + ", expected >= 2");
  const int K = order;
  IntegrationResult r;
  const int T = static_cast<int>(outs.size());
  r.t.resize(T);
  r.x.setZero(T, n);
  const double t0 = outs.front(), tend = outs.back();
  std::vector<double> edges{t0};
  for (double b : breakpoints)
    if (b > t0 && b < tend) edges.push_back(b);
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  edges.push_back(tend);

  // A change of a coefficient function this small moves the solution far below the
  // tolerances: a piece whose functions vary less is constant, and terms of a fit this
  // small are dropped.
  // The floor: the zero-order motion is integrated to 1e-12, and the accelerations its
  // interpolant gives wander by ~1e-12 of their size.
  auto negligible = [&](int i) { return std::max(1e-2 * options.rtol, 1e-11) * coefficients.scale(i); };
  Eigen::VectorXd y = Eigen::VectorXd::Zero(n), c(nb), u(m), xb(n);
  std::vector<double> knots = coefficients.nominal->knots();
  std::sort(knots.begin(), knots.end());
  int next_out = 0;
  double theta0 = 0.0;
  long long per_term = step_work(n, IntegratorOptions::Method::Adams);
  long steps_since_output = 0;  // for max_steps
  // The state `state` (y) at an output time, back in inertial coordinates.
  auto record = [&](double t, double mid, const Eigen::VectorXd& state) -> bool {
    const Instant at{t, mid};
    coefficients.at(at, c, theta0, u);
    xb.noalias() = form.S * state;
    turn(xb, planar::rot(theta0), N);
    r.t(next_out) = t;
    r.x.row(next_out) = xb.transpose();
    ++next_out;
    if (!xb.allFinite()) {
      r.status = IntegrationStatus::Failed;
      r.message = "the first-order state is not finite at t = " + util::format_number(t, 6) + " s";
      r.failure_time = t;
      return false;
    }
    if (range_check) {
      const std::string why = range_check(at, xb);
      if (!why.empty()) {
        r.status = IntegrationStatus::OutOfRange;
        r.message = "at t = " + util::format_number(t, 6) + " s: " + why;
        r.failure_time = t;
        return false;
      }
    }
    if (options.progress) options.progress(t);
    steps_since_output = 0;
    return true;
  };
  auto finish = [&]() {
    r.t.conservativeResize(next_out);
    r.x.conservativeResize(next_out, n);
    return r;
  };
  if (!record(t0, t0, y)) return finish();
  auto fail_at = [&](double t, const std::string& why) {
    r.status = IntegrationStatus::Failed;
    r.message = why + " at t = " + util::format_number(t, 6) + " s";
    r.failure_time = t;
    return finish();
  };
  // The step budgets: max_total_steps and max_steps count steps (a Taylor step, the
  // application of an exponential), the study's budget products (a Taylor step its terms,
  // an exponential exp_cost, its application one); false when spent.
  const long exp_cost = 10L * n;  // about the products of one exponential (Padé, squarings)
  auto charge = [&](long terms, double t, bool step) {
    if (step) ++steps_since_output;
    if (step && options.max_total_steps > 0 && r.steps >= options.max_total_steps) {
      fail_at(t, "stopped: the integration's step budget, max_total_steps = " + std::to_string(options.max_total_steps) +
                     ", is spent");
      return false;
    }
    if (steps_since_output > options.max_steps) {
      fail_at(t, "stopped: more than max_steps = " + std::to_string(options.max_steps) + " steps between two outputs");
      return false;
    }
    if (options.budget) {
      if (options.budget->steps_left(per_term * terms) < 1) {
        options.budget->mark_exhausted();
        fail_at(t, "stopped: " + options.budget->spent_message());
        return false;
      }
      options.budget->charge(per_term * terms);
    }
    return true;
  };

  // Chebyshev nodes on [0, 1]: values there → Chebyshev coefficients (well conditioned,
  // so a polynomial of low degree shows as one: its higher coefficients are round-off)
  // → the monomial coefficients in σ of the series cut after its last coefficient that
  // matters.
  constexpr int kFit = 10;
  Eigen::VectorXd nodes(kFit);
  Eigen::MatrixXd cheb(kFit, kFit), mono = Eigen::MatrixXd::Zero(kFit, kFit);
  for (int l = 0; l < kFit; ++l) {
    const double angle = M_PI * (l + 0.5) / kFit;
    nodes(l) = 0.5 * (1.0 - std::cos(angle));  // x = 2σ - 1 = -cos(angle)
    for (int j = 0; j < kFit; ++j) cheb(j, l) = (j == 0 ? 1.0 : 2.0) / kFit * std::cos(j * (M_PI - angle));
  }
  // T_j(2σ - 1) in powers of σ: T_0 = 1, T_1 = 2σ - 1, T_{j+1} = 2 (2σ - 1) T_j - T_{j-1}
  mono(0, 0) = 1.0;
  mono(0, 1) = -1.0;
  mono(1, 1) = 2.0;
  for (int j = 1; j + 1 < kFit; ++j)
    for (int k = 0; k < kFit; ++k)
      mono(k, j + 1) = (k > 0 ? 4.0 * mono(k - 1, j) : 0.0) - 2.0 * mono(k, j) - mono(k, j - 1);
  Eigen::MatrixXd samples(kFit, nb), coef(kFit, nb), chebc(kFit, nb);
  std::vector<int> degree(nb);
  Eigen::MatrixXd X(n, K + 1);  // Taylor terms in σ = (t - t_n) / H
  std::vector<double> sizes(static_cast<std::size_t>(K) + 1);  // their weighted sizes, from first_sized on
  const int first_sized = std::max(1, std::min(kMinOrder, K) - 1);
  // The terms whose functions are constant on a step are summed into one matrix C0 on
  // the union of their patterns (kept for the last set of such terms: it changes between
  // pieces only); the others are applied one by one, each to Σ_j c_ij X_{k-j} on the
  // columns it uses.
  std::vector<SparseEntries> term(nb);
  for (int i = 0; i < nb; ++i)
    if (form.A[i].size()) term[i] = SparseEntries(form.A[i]);
  std::vector<bool> folded(nb, false), pattern_of(nb, false);
  SparseEntries C0;
  std::vector<std::vector<double>> on_C0(nb);  // each folded term's values on C0's pattern
  auto make_C0 = [&]() {
    Eigen::MatrixXd any = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < nb; ++i)
      if (folded[i]) any += form.A[i].cwiseAbs();
    C0 = SparseEntries(any);
    for (int i = 0; i < nb; ++i) {
      on_C0[i].clear();
      if (!folded[i]) continue;
      for (int e = 0; e < C0.size(); ++e) on_C0[i].push_back(form.A[i](C0.row[e], C0.col[e]));
    }
    pattern_of = folded;
  };
  std::vector<int> varying;
  Eigen::MatrixXd G(n, kFit);  // Σ_i c_ij g_i
  Eigen::VectorXd acc(n), v(n);
  const double norm_A0 = form.A[0].cwiseAbs().rowwise().sum().maxCoeff();
  const double h_max = kMaxStepNorm / std::max(norm_A0, 1e-300);

  for (std::size_t p = 0; p + 1 < edges.size(); ++p) {
    const double a = edges[p], b = edges[p + 1], mid = 0.5 * (a + b);
    // Constant piece? Then exact exponentials of [[A, g], [0, 0]]. Sampled at both ends
    // and at 15 points spaced by the golden ratio (equal spacing can alias a rotation:
    // whole turns between samples); and a piece that turns (θ0' not negligible) is not
    // constant when u cos θ0 or u sin θ0 is not zero (a, the acceleration in body axes,
    // can be constant while the body turns: a free spin about o off the mass centre).
    constexpr int kProbe = 17;
    Eigen::MatrixXd cs(kProbe, nb);
    for (int k = 0; k < kProbe; ++k) {
      const double f = k == 0 ? 0.0 : k == 1 ? 1.0 : std::fmod(0.5 + 0.6180339887498949 * k, 1.0);
      Eigen::VectorXd ck(nb);
      coefficients.at(Instant{a + (b - a) * f, mid}, ck, theta0, u);
      cs.row(k) = ck.transpose();
    }
    bool constant = true;
    for (int i = 0; i < nb && constant; ++i)
      constant = cs.col(i).maxCoeff() - cs.col(i).minCoeff() <= negligible(i);
    const bool turning = cs.col(1).cwiseAbs().maxCoeff() > negligible(1);
    for (int i = kFixed; i < nb && constant && turning; ++i)
      if (i >= kFixed && (i - kFixed) % 3 != 0)
        constant = cs.col(i).cwiseAbs().maxCoeff() <= negligible(i);
    double t = a;
    if (constant) {
      Eigen::MatrixXd At = Eigen::MatrixXd::Zero(n + 1, n + 1);
      const Eigen::VectorXd cm = cs.row(2).transpose();  // at a + 0.736 (b - a)
      for (int i = 0; i < nb; ++i) {
        if (form.A[i].size()) At.topLeftCorner(n, n) += cm(i) * form.A[i];
        if (form.g[i].size()) At.topRightCorner(n, 1) += cm(i) * form.g[i];
      }
      Eigen::MatrixXd E;
      double cached = -1.0;
      Eigen::VectorXd ya(n + 1);
      while (t < b) {
        const double target = next_out < T && outs[next_out] <= b ? outs[next_out] : b;
        const double d = target - t;
        // Output times a step apart differ by a few ulps of t: one exponential serves them
        // all (a spacing off by 1e-12 of itself moves a phase by ω 1e-12 Δ, far below any
        // tolerance).
        if (!(std::abs(d - cached) <= 1e-12 * cached)) {
          E = (At * d).exp();
          cached = d;
          r.rhs_evaluations += exp_cost;
          if (!charge(exp_cost, t, false)) return finish();
        }
        if (!charge(1, t, true)) return finish();  // each application is a step
        ya << y, 1.0;
        y = E.topRows(n) * ya;
        if (!y.allFinite()) return fail_at(t, "the exponential of the piece's constant model is not finite");
        ++r.steps;
        t = target;
        if (next_out < T && outs[next_out] == t && !record(t, mid, y)) return finish();
        if (t == b) break;
      }
      continue;
    }
    // Taylor steps: the coefficient functions fitted on each step, the terms by the
    // recurrence (k+1) X_{k+1} = H [Σ_i A_i Σ_j c_ij X_{k-j} + Σ_i c_ik g_i].
    const double h_limit = options.max_step > 0.0 ? std::min(options.max_step, h_max) : h_max;
    double h_want = 4.0 / std::max(norm_A0, 1e-300);  // the step the error test asks for
    // the nominal's knots inside the piece: a step ends at the next one (a fit across a
    // jump of the third derivative drifts: 3e-9 rad in θ over 3 s at NOA 6)
    auto knot = std::upper_bound(knots.begin(), knots.end(), a);
    double tail_before = std::numeric_limits<double>::infinity(), tail_H = tail_before;  // the fit check's last refusal
    double noise_tail = 0.0;  // the tails (over negligible) found to be the nominal's noise in this piece
    while (t < b) {
      h_want = std::min(h_want, h_limit);
      while (knot != knots.end() && *knot <= t) ++knot;
      const double stop = knot != knots.end() && *knot < b ? *knot : b;
      // to the stop in one step when it is at most a quarter further than wanted (and
      // within max_step), else in two equal ones when one wanted step would leave a
      // sliver before it
      const double d = stop - t;
      const double H = d < 1.25 * h_want ? (d <= h_limit * (1.0 + 1e-9) ? d : 0.5 * d) : h_want;
      if (!(H > 4.0 * std::numeric_limits<double>::epsilon() * std::max(std::abs(t), 1.0)))
        return fail_at(t, "Taylor steps fell to round-off (the coefficient functions or the terms cannot be resolved)");
      for (int l = 0; l < kFit; ++l) {
        Eigen::VectorXd cl(nb);
        coefficients.at(Instant{t + nodes(l) * H, mid}, cl, theta0, u);
        samples.row(l) = cl.transpose();
      }
      chebc.noalias() = cheb * samples;
      if (!chebc.allFinite()) return fail_at(t, "the nominal motion or the commands are not finite");
      // The fit must resolve every function on the step: its last two Chebyshev
      // coefficients negligible, else a shorter step; unless halving the step did not
      // shrink them (a smooth function's fall 2^9 times): then they are the noise of the
      // nominal itself (its interpolated accelerations carry the round-off of positions
      // over h², ~1e-10 of θ0'' after some turns), which no step resolves.
      double worst_tail = 0.0;
      for (int i = 0; i < nb; ++i)
        worst_tail = std::max(worst_tail, (std::abs(chebc(kFit - 1, i)) + std::abs(chebc(kFit - 2, i))) / negligible(i));
      if (worst_tail > std::max(1.0, noise_tail)) {
        if (!(H < 0.75 * tail_H && worst_tail > 0.1 * tail_before)) {
          tail_before = worst_tail;
          tail_H = H;
          h_want = 0.5 * H;
          continue;
        }
        noise_tail = 4.0 * worst_tail;  // the piece's noise: later steps need not retry it
      }
      tail_before = std::numeric_limits<double>::infinity();
      tail_H = std::numeric_limits<double>::infinity();
      for (int i = 0; i < nb; ++i) {
        const double big = chebc.col(i).cwiseAbs().maxCoeff();
        int deg = kFit - 1;
        while (deg >= 0 && std::abs(chebc(deg, i)) <= std::max(1e-14 * big, negligible(i))) --deg;
        degree[i] = deg;  // -1: the function is zero on this step
        coef.col(i).setZero();
        if (deg >= 0)
          coef.col(i).head(deg + 1).noalias() = mono.topLeftCorner(deg + 1, deg + 1) * chebc.col(i).head(deg + 1);
      }
      // This step's matrices and forcing polynomials.
      varying.clear();
      for (int i = 0; i < nb; ++i) {
        folded[i] = form.A[i].size() && degree[i] == 0;
        if (form.A[i].size() && degree[i] > 0) varying.push_back(i);
      }
      if (folded != pattern_of || C0.row.empty()) make_C0();
      std::fill(C0.val.begin(), C0.val.end(), 0.0);
      for (int i = 0; i < nb; ++i) {
        if (!folded[i]) continue;
        const double ci = coef(0, i);
        for (std::size_t e = 0; e < C0.val.size(); ++e) C0.val[e] += ci * on_C0[i][e];
      }
      C0.refresh();
      int Dg = -1;
      G.setZero();
      for (int i = 0; i < nb; ++i) {
        if (!form.g[i].size()) continue;
        for (int j = 0; j <= degree[i]; ++j) G.col(j) += coef(j, i) * form.g[i];
        Dg = std::max(Dg, degree[i]);
      }
      // Terms until the last two are small enough for the whole step (at most K).
      Eigen::VectorXd weight = ((options.atol + options.rtol * y.array().abs()).inverse()).matrix();
      auto size_of = [&](int j) { return X.col(j).cwiseAbs().cwiseProduct(weight).maxCoeff(); };
      X.col(0) = y;
      int used = K;  // the order used
      for (int k = 0; k < K; ++k) {
        if (k <= Dg)
          acc = G.col(k);
        else
          acc.setZero();
        C0.multiply_add(&X(0, k), acc.data());
        for (int i : varying) {
          const int top = std::min(k, degree[i]);
          v = coef(0, i) * X.col(k);
          for (int j = 1; j <= top; ++j) v += coef(j, i) * X.col(k - j);
          term[i].multiply_add(v.data(), acc.data());
        }
        X.col(k + 1) = (H / (k + 1)) * acc;
        if (k + 1 < first_sized) continue;
        sizes[static_cast<std::size_t>(k) + 1] = size_of(k + 1);  // each term's size once
        if (k + 1 >= kMinOrder && k + 1 > Dg && sizes[static_cast<std::size_t>(k)] <= kLocalError &&
            sizes[static_cast<std::size_t>(k) + 1] <= kLocalError) {
          used = k + 1;
          break;
        }
      }
      r.rhs_evaluations += used;
      if (!charge(used, t, true)) return finish();
      // Step: the last two terms at σ meet the tolerances (weights from the step's start).
      // A term that is not finite makes its size NaN (or infinite): the series has failed.
      double sigma = std::numeric_limits<double>::infinity();
      for (int j : {used - 1, used}) {
        const double e = sizes[static_cast<std::size_t>(j)];
        if (!std::isfinite(e)) return fail_at(t, "the Taylor series of the first-order model is not finite");
        if (e > 0.0) sigma = std::min(sigma, std::pow(kLocalError / e, 1.0 / j));
      }
      if (used == K) sigma *= 0.9;
      const double step = std::min(sigma, 1.0);
      const bool to_stop = step >= 1.0 && H == stop - t;
      const double t_new = to_stop ? stop : (step >= 1.0 ? t + H : t + step * H);
      // The series at σ by Horner's rule: at the outputs within the step, then at its end.
      auto series_at = [&](double sigma_at) {
        Eigen::VectorXd sum = X.col(used);
        for (int k = used - 1; k >= 0; --k) sum = sum * sigma_at + X.col(k);
        return sum;
      };
      while (next_out < T && outs[next_out] <= t_new && outs[next_out] <= b)
        if (!record(outs[next_out], mid, series_at((outs[next_out] - t) / H))) return finish();
      const Eigen::VectorXd yn = series_at(step);
      if (!yn.allFinite()) return fail_at(t, "the Taylor series of the first-order model is not finite");  // every term is in it
      y = yn;
      t = t_new;
      ++r.steps;
      // a step cut short by a knot or the piece's end says nothing against the longer one
      if (step < 1.0)
        h_want = step * H;
      else if (!(to_stop && H < h_want))
        h_want = H * std::min(sigma, 2.0);
    }
  }
  r.status = IntegrationStatus::Completed;
  return finish();
}

}  // namespace freeflex::detail

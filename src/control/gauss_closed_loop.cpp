// Fixed-step Gauss-Legendre collocation for the saturated closed loop on the first-order
// model (gauss_closed_loop.hpp).
#include "control/gauss_closed_loop.hpp"

#include <algorithm>
#include <string>

#include "util/format.hpp"

namespace freeflex::detail {
namespace {

using T = GaussTableau;

std::string fmt(double v) { return util::format_number(v, 12); }

class Stepper {
 public:
  Stepper(const SaturatedLinearSystem& sys, const GaussOptions& o, IntegrationResult& r)
      : sys_(sys), o_(o), r_(r), n_(sys.dim), big_(T::s * sys.dim, T::s * sys.dim), rhs_(T::s * sys.dim) {
    for (int j = 0; j < T::s; ++j) {
      M_[j].resize(n_, n_);
      f_[j].resize(n_);
      held_[j].setZero(sys.inputs);
      seen_[j].setZero(sys.inputs);
    }
  }

  /// x at t0 -> x at t0 + h; a step whose saturation pattern is not the same at its start,
  /// its stages and its end is halved (up to 40 times: 2^-40 of its length).
  bool step(double t0, double h, double mid, Eigen::VectorXd& x, int depth = 0) {
    if (o_.max_total_steps > 0 && r_.steps >= o_.max_total_steps)
      return fail(t0, "the integration's step budget, max_total_steps = " + std::to_string(o_.max_total_steps) +
                          ", is spent; the simulated span needs more work than it allows");
    const long long work = 40LL * n_ * n_ * n_;
    if (o_.budget && o_.budget->steps_left(work) < 1) {
      o_.budget->mark_exhausted();
      return fail(t0, o_.budget->spent_message());
    }
    if (o_.budget) o_.budget->charge(work);
    ++r_.steps;
    const int n = n_;
    sys_.pattern(Instant{t0, mid}, x, start_);
    for (int j = 0; j < T::s; ++j) held_[j] = start_;
    bool settled = false;
    for (int iteration = 0; iteration < 20 && !settled; ++iteration) {
      big_.setIdentity();
      for (int j = 0; j < T::s; ++j) {
        ++r_.rhs_evaluations;
        if (!sys_.matrices(Instant{t0 + T::c[j] * h, mid}, held_[j], M_[j], f_[j]))
          return fail(t0, "the closed-loop first-order model is not finite");
      }
      for (int i = 0; i < T::s; ++i) {
        auto r = rhs_.segment(i * n, n);
        r = x;
        for (int j = 0; j < T::s; ++j) {
          const double w = h * T::a[i][j];
          big_.block(i * n, j * n, n, n) -= w * M_[j];
          r += w * f_[j];
        }
      }
      lu_.compute(big_);
      X_ = lu_.solve(rhs_);
      if (!X_.allFinite()) return fail(t0, "the collocation system is singular");
      settled = true;
      for (int j = 0; j < T::s; ++j) {
        sys_.pattern(Instant{t0 + T::c[j] * h, mid}, X_.segment(j * n, n), seen_[j]);
        if (seen_[j] != held_[j]) settled = false;
        held_[j] = seen_[j];
      }
    }
    Eigen::VectorXd x_new = x;
    for (int j = 0; j < T::s; ++j) {
      x_new.noalias() += (h * T::b[j]) * (M_[j] * X_.segment(j * n, n));
      x_new += (h * T::b[j]) * f_[j];
    }
    if (!x_new.allFinite()) return fail(t0, "the state became non-finite");
    bool uniform = settled;
    for (int j = 0; j < T::s; ++j) uniform = uniform && held_[j] == start_;
    Eigen::VectorXi end;
    sys_.pattern(Instant{t0 + h, mid}, x_new, end);
    uniform = uniform && end == start_;
    if (uniform || depth >= 40) {
      x = x_new;
      return true;
    }
    return step(t0, 0.5 * h, mid, x, depth + 1) && step(t0 + 0.5 * h, 0.5 * h, mid, x, depth + 1);
  }

 private:
  bool fail(double t, const std::string& why) {
    r_.failure_time = t;
    r_.message = "Gauss collocation failed at t = " + fmt(t) + ": " + why;
    return false;
  }

  const SaturatedLinearSystem& sys_;
  const GaussOptions& o_;
  IntegrationResult& r_;
  int n_;
  std::array<Eigen::MatrixXd, T::s> M_;
  std::array<Eigen::VectorXd, T::s> f_;
  std::array<Eigen::VectorXi, T::s> held_, seen_;
  Eigen::VectorXi start_;
  Eigen::MatrixXd big_;
  Eigen::VectorXd rhs_, X_;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_;
};

}  // namespace

IntegrationResult integrate_gauss(const SaturatedLinearSystem& system, const Eigen::Ref<const Eigen::VectorXd>& x0,
                                  const std::vector<double>& output_times, const std::vector<double>& breakpoints,
                                  const std::vector<double>& grid, const GaussOptions& options) {
  const int n = system.dim;
  const std::size_t n_out = output_times.size();
  IntegrationResult result;
  result.t.resize(static_cast<Eigen::Index>(n_out));
  result.x.resize(static_cast<Eigen::Index>(n_out), n);
  Eigen::Index rows = 0;
  Eigen::VectorXd x = x0;
  auto record = [&](double t) {
    result.t(rows) = t;
    result.x.row(rows) = x.transpose();
    ++rows;
    if (options.progress) options.progress(t);
  };
  auto finish = [&](bool ok) {
    result.status = ok ? IntegrationStatus::Completed : IntegrationStatus::Failed;
    result.t.conservativeResize(rows);
    result.x.conservativeResize(rows, n);
    return result;
  };
  if (n_out == 0) return finish(true);
  const double t0 = output_times.front(), tend = output_times.back();
  record(t0);
  // pieces as integrate() cuts them
  std::vector<double> bounds{t0};
  for (double b : breakpoints)
    if (b > t0 && b < tend) bounds.push_back(b);
  bounds.push_back(tend);
  std::sort(bounds.begin() + 1, bounds.end() - 1);
  bounds.erase(std::unique(bounds.begin(), bounds.end()), bounds.end());

  Stepper stepper(system, options, result);
  std::size_t next = 1;
  for (std::size_t k = 0; k + 1 < bounds.size(); ++k) {
    const double a = bounds[k], b = bounds[k + 1], mid = 0.5 * (a + b);
    std::vector<double> edges{a};
    if (!roundoff_span(a, b)) {
      for (double t : output_times)
        if (t > a && t < b) edges.push_back(t);
      for (double t : grid)
        if (t > a && t < b) edges.push_back(t);
    }
    edges.push_back(b);
    std::sort(edges.begin() + 1, edges.end() - 1);
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    for (std::size_t e = 0; e + 1 < edges.size(); ++e) {
      const double e0 = edges[e], e1 = edges[e + 1];
      if (!roundoff_span(e0, e1)) {  // a roundoff-sized interval leaves the state as it is
        const double h = (e1 - e0) / options.steps;
        for (int i = 0; i < options.steps; ++i) {
          const double ta = e0 + i * h, tb = i + 1 == options.steps ? e1 : e0 + (i + 1) * h;
          if (!stepper.step(ta, tb - ta, mid, x)) return finish(false);
        }
      }
      while (next < n_out && output_times[next] <= e1) record(output_times[next++]);
    }
  }
  return finish(true);
}

}  // namespace freeflex::detail

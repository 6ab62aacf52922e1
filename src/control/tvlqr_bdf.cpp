// The BDF sweep of the TV-LQR (control/tvlqr_sweep.hpp): CVODES on the packed Riccati
// state piece by piece, and the same integrator for single steps of the exponential sweep.
#include <algorithm>
#include <cmath>
#include <utility>

#include <cvodes/cvodes.h>

#include "control/tvlqr_sweep.hpp"
#include "util/format.hpp"

namespace freeflex::detail {

namespace {
std::string fmt(double v) { return util::format_number(v, 10); }
}  // namespace

void init_riccati_data(const Sweep& sw, LtvEvaluator* model, RiccatiData& d) {
  d.model = model;
  d.tf = sw.tf;
  d.n = sw.n;
  d.m = sw.m;
  d.Rllt.compute(sw.R);
  d.max_condition = sw.options->modal_max_condition;
  d.piece_mid_t = 0.5 * (sw.bounds[sw.bounds.size() - 2] + sw.bounds.back());
  d.sigma = std::max(sw.result->Qf.cwiseAbs().maxCoeff(), sw.Q.cwiseAbs().maxCoeff());
  if (!(d.sigma > 0.0)) d.sigma = 1.0;
  d.Qs = sw.Q / d.sigma;
}

void record_packed(const Sweep& sw, RiccatiData& d, int idx, const double* y) {
  TvlqrResult& res = *sw.result;
  const int n = sw.n, nt = tri_size(n);
  Eigen::MatrixXd Psym;
  unpack(y, n, Psym);
  Psym *= d.sigma;
  Eigen::Map<const Eigen::VectorXd> sh(y + nt, n);
  Eigen::MatrixXd K = d.B().transpose() * Psym;
  d.Rllt.solveInPlace(K);
  res.K[idx] = std::move(K);  // stored as computed: no second allocation
  Eigen::VectorXd ff = d.B().transpose() * sh;
  d.Rllt.solveInPlace(ff);
  res.feedforward.row(idx) = -d.sigma * ff.transpose();
  if (sw.options->store_riccati) res.P[idx] = Psym;
  if (idx == 0) {
    res.P0 = Psym;
    res.s0 = d.sigma * sh;
    res.c0 = d.sigma * y[nt + n];
  }
}

BdfRiccati::BdfRiccati(RiccatiData& d, const TvlqrOptions& o, double tau0, const double* y0)
    : d_(d),
      cv_(tri_size(d.n) + d.n + 1, cvodes::Integrator::Method::Bdf, "solve_tvlqr"),
      budget_(o.budget.get()),
      work_(riccati_step_work(d.n)),
      max_steps_(o.max_steps) {
  const long dim = cv_.dim();
  std::copy(y0, y0 + dim, cv_.state());
  cv_.init(freeflex_riccati_rhs, tau0, &d);
  cv_.scalar_tolerances(o.rtol, o.atol);
  cv_.max_num_steps(o.max_steps);
  direct_ = std::make_unique<DirectSolverContent>(DirectSolverContent{&d, cv_.memory()});
  if (o.newton_solver == TvlqrOptions::NewtonSolver::Lyapunov)
    cv_.matrix_embedded(make_direct_solver(cv_.context(), direct_.get()));
  else
    cv_.gmres(10, freeflex_riccati_psetup, freeflex_riccati_psolve, freeflex_riccati_jtsetup, freeflex_riccati_jtimes);
}

std::string BdfRiccati::advance(double tau_a, double tau_b, bool restart, const std::vector<double>& taus,
                                const std::function<bool(int)>& out) {
  if (restart) cv_.reinit(tau_a);
  cv_.stop_time(tau_b);
  const cvodes::Counters base = cv_.counters();  // CVODE's counters run from its last (re)start
  auto add_stats = [&]() {
    const cvodes::Counters c = cv_.counters();
    steps_ += c.steps - base.steps;
    rhs_ += c.rhs_evaluations - base.rhs_evaluations;
    lin_ += c.linear_iterations - base.linear_iterations;
  };
  const long dim = cv_.dim();
  double now = tau_a;
  for (std::size_t k = 0; k < taus.size(); ++k) {
    // A stop within round-off of where the integrator stands (a grid time the previous step
    // ended on, up to the rounding of τ): its state is the current one; CVODE would refuse
    // it as too close (CV_TOO_CLOSE).
    if (taus[k] - now <= 1e-12 * std::max(1.0, std::abs(taus[k]))) {
      if (!out(static_cast<int>(k))) {
        add_stats();
        return d_.error.empty() ? "recording the law failed at t = " + fmt(d_.tf - now) + " s" : d_.error;
      }
      continue;
    }
    bool by_budget = false;
    const cvodes::Integrator::Advance step = cv_.advance(taus[k], max_steps_, budget_, work_, by_budget);
    if (step.flag == CV_TOO_MUCH_WORK && by_budget) {
      add_stats();
      return "stopped at t = " + fmt(d_.tf - step.reached) + " s: " + budget_->spent_message();
    }
    if (step.flag < 0) {
      add_stats();
      std::string msg = "CVODES failed at t = " + fmt(d_.tf - step.reached) + " s: " + cvodes::Integrator::flag_name(step.flag);
      // CVODES's own message counts the backward time τ = tf - t.
      const std::string why = !d_.error.empty()         ? d_.error
                              : cv_.last_error().empty() ? ""
                                                         : cv_.last_error() + " [τ = tf - t]";
      if (!why.empty()) msg += " (" + why + ")";
      return msg;
    }
    if (!Eigen::Map<const Eigen::VectorXd>(cv_.state(), dim).allFinite()) {
      add_stats();
      return "the Riccati solution became non-finite at t = " + fmt(d_.tf - step.reached) + " s";
    }
    now = step.reached;
    if (!out(static_cast<int>(k))) {
      add_stats();
      return d_.error.empty() ? "recording the law failed at t = " + fmt(d_.tf - step.reached) + " s" : d_.error;
    }
  }
  add_stats();
  return "";
}

void sweep_bdf(const Sweep& sw) {
  TvlqrResult& res = *sw.result;
  const TvlqrOptions& o = *sw.options;
  RiccatiData d;
  init_riccati_data(sw, sw.model, d);
  const int n = sw.n, nt = tri_size(n), G = static_cast<int>(sw.grid.size());
  Eigen::VectorXd y0 = Eigen::VectorXd::Zero(nt + n + 1);
  pack(res.Qf / d.sigma, y0.data());
  BdfRiccati bdf(d, o, 0.0, y0.data());
  auto finish = [&](TvlqrResult::Status st, std::string msg) {
    res.status = st;
    res.message = std::move(msg);
    res.steps = bdf.steps();
    res.rhs_evaluations = bdf.rhs_evaluations();
    res.linear_iterations = bdf.linear_iterations();
    res.preconditioner_setups = d.setups;
    res.modal_setups = d.modal_setups;
  };
  int idx = G - 1;
  if (!d.eval(sw.tf)) return finish(TvlqrResult::Status::IntegrationFailed, d.error);
  record_packed(sw, d, idx, bdf.state());
  --idx;
  const int pieces = static_cast<int>(sw.bounds.size()) - 1;
  for (int p = pieces - 1; p >= 0; --p) {
    const double a_t = sw.bounds[p], b_t = sw.bounds[p + 1];
    const double tau_a = sw.tf - b_t, tau_b = sw.tf - a_t;
    d.piece_mid_t = 0.5 * (a_t + b_t);
    d.cached = false;
    d.have_pre = false;  // the model may jump at a breakpoint: refresh the frozen closed loop
    std::vector<double> taus;
    std::vector<int> which;
    for (int i = idx; i >= 0 && sw.grid[i] >= a_t; --i) {
      taus.push_back(sw.grid[i] == a_t ? tau_b : sw.tf - sw.grid[i]);
      which.push_back(i);
    }
    const std::string failure = bdf.advance(tau_a, tau_b, p != pieces - 1, taus, [&](int k) {
      const int i = which[k];
      if (!d.eval(sw.grid[i])) return false;
      record_packed(sw, d, i, bdf.state());
      if (o.progress) o.progress(sw.tf - sw.grid[i]);
      return true;
    });
    if (!failure.empty()) return finish(TvlqrResult::Status::IntegrationFailed, failure);
    idx -= static_cast<int>(taus.size());
  }
  finish(TvlqrResult::Status::Solved, "solved");
}

}  // namespace freeflex::detail

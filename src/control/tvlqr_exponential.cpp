// The exponential sweep of the TV-LQR (control/tvlqr_sweep.hpp): exponential collocation
// steps (control/riccati_exponential.hpp) piece by piece in the model's rotating frame,
// the law at the grid times inside each step, and BDF for a step whose frozen closed loop
// has no well-conditioned block-diagonal form.
#include <algorithm>
#include <cmath>

#include "control/riccati_exponential.hpp"
#include "control/tvlqr_sweep.hpp"
#include "util/format.hpp"

namespace freeflex::detail {

namespace {

std::string fmt(double v) { return util::format_number(v, 10); }

/// Rows (i, i+1) of M ← [[a, b], [c, d]] · rows.
template <typename M>
void mix_rows(M& m, int i, double a, double b, double c, double d) {
  for (int j = 0; j < m.cols(); ++j) {
    const double x = m(i, j), y = m(i + 1, j);
    m(i, j) = a * x + b * y;
    m(i + 1, j) = c * x + d * y;
  }
}
/// Columns (i, i+1) of M ← columns · [[a, b], [c, d]].
void mix_cols(Eigen::MatrixXd& m, int i, double a, double b, double c, double d) {
  for (int r = 0; r < m.rows(); ++r) {
    const double x = m(r, i), y = m(r, i + 1);
    m(r, i) = a * x + c * y;
    m(r, i + 1) = b * x + d * y;
  }
}

/// The model in the frame's coordinates: A_b = Tᵀ A T − Tᵀ T', B_b = Tᵀ B, g_b = Tᵀ g
/// (T rotates each pair by C = [[cos θ, −sin θ], [sin θ, cos θ]]; Tᵀ T' = θ' [[0, −1], [1, 0]]).
class FrameEvaluator : public LtvEvaluator {
 public:
  FrameEvaluator(LtvEvaluator& inner, const RotatingFrame& frame) : inner_(inner), frame_(frame) {}
  const StateSpace& eval(const Instant& at) override {
    const StateSpace& s = inner_.eval(at);
    out_.A = s.A;
    out_.B = s.B;
    out_.g = s.g;
    double th = 0.0, rate = 0.0;
    frame_.angle(at, th, rate);
    const double c = std::cos(th), sn = std::sin(th);
    for (int i : frame_.pairs) {
      if (i + 1 >= out_.A.rows()) continue;  // sizes are checked by the caller
      mix_rows(out_.A, i, c, sn, -sn, c);
      mix_rows(out_.B, i, c, sn, -sn, c);
      mix_rows(out_.g, i, c, sn, -sn, c);
      mix_cols(out_.A, i, c, -sn, sn, c);
      out_.A(i, i + 1) += rate;
      out_.A(i + 1, i) -= rate;
    }
    return out_;
  }

 private:
  LtvEvaluator& inner_;
  const RotatingFrame& frame_;
  StateSpace out_;
};

}  // namespace

void sweep_exponential(const Sweep& sw) {
  TvlqrResult& res = *sw.result;
  const TvlqrOptions& o = *sw.options;
  std::unique_ptr<FrameEvaluator> framed;
  if (sw.frame) framed = std::make_unique<FrameEvaluator>(*sw.model, *sw.frame);
  RiccatiData d;
  init_riccati_data(sw, framed ? static_cast<LtvEvaluator*>(framed.get()) : sw.model, d);
  const int n = sw.n, nt = tri_size(n), G = static_cast<int>(sw.grid.size());
  const double span = sw.tf - sw.t0;
  // The work of an exponential step, accepted or not, in the budget's units: it took the CPU
  // time of 15 BDF steps at NOA = 6 and 12 at NOA = 20 (bench/tvlqr_accuracy); charged as 16.
  const long long step_work = 16 * riccati_step_work(n);

  // frame rotations at time t: body → physical (to_physical) and back
  auto angle_at = [&](double t, double& c, double& s) {
    double th = 0.0, rate = 0.0;
    if (sw.frame) sw.frame->angle(Instant{t, d.piece_mid_t}, th, rate);
    c = std::cos(th);
    s = std::sin(th);
  };
  auto rotate_P = [&](Eigen::MatrixXd& P, double t, bool to_physical) {  // T P Tᵀ or Tᵀ P T
    if (!sw.frame) return;
    double c, s;
    angle_at(t, c, s);
    const double sg = to_physical ? 1.0 : -1.0;
    for (int i : sw.frame->pairs) {
      mix_rows(P, i, c, -sg * s, sg * s, c);
      mix_cols(P, i, c, sg * s, -sg * s, c);
    }
  };
  // the law at grid index idx from the σ-scaled body-frame Gᵀ P, s, c (and P)
  auto record = [&](int idx, Eigen::MatrixXd& GtP, Eigen::VectorXd& s, double c, Eigen::MatrixXd* P) {
    const double t = sw.grid[idx];
    double cs = 1.0, sn = 0.0;
    angle_at(t, cs, sn);
    Eigen::MatrixXd K = d.sigma * GtP;
    d.Rllt.matrixU().solveInPlace(K);  // σ R⁻¹ Bᵀ P = σ L⁻ᵀ Gᵀ P
    if (sw.frame)
      for (int i : sw.frame->pairs) mix_cols(K, i, cs, sn, -sn, cs);  // K Tᵀ
    res.K[idx] = K;
    Eigen::VectorXd ff = d.G.transpose() * s;
    d.Rllt.matrixU().solveInPlace(ff);
    res.feedforward.row(idx) = -d.sigma * ff.transpose();
    if (P) {
      *P *= d.sigma;
      rotate_P(*P, t, true);
      if (o.store_riccati) res.P[idx] = *P;
      if (idx == 0) res.P0 = *P;
    }
    if (idx == 0) {
      if (sw.frame)
        for (int i : sw.frame->pairs) mix_rows(s, i, cs, -sn, sn, cs);  // T s
      res.s0 = d.sigma * s;
      res.c0 = d.sigma * c;
    }
  };

  ExponentialRiccati::Settings set;
  set.rtol = o.rtol;
  set.atol = o.atol;
  // The exponential steps accept a form 100 times worse conditioned than BDF's Newton solves
  // do (whose alternative, the Schur form, costs only speed): at NOA = 40 the moment
  // example's loop has κ₁ between 1e6 and 1e8 at every step, and BDF, the alternative here,
  // took 333 s where the exponential sweep takes 0.9 s; κ₁ = 1e8 still leaves the products
  // in the form 1e-8 of relative round-off.
  set.max_condition = 100.0 * o.modal_max_condition;
  ExponentialRiccati ex(d, set);
  std::unique_ptr<BdfRiccati> bdf;
  long accepted = 0, rejected = 0, fallbacks = 0;
  // BDF took the last step and stands at its end: the next fallback continues its
  // integration instead of restarting it (a restart begins at order 1 with tiny steps;
  // at NOA = 40, where no step of the moment example has a well-conditioned form,
  // restarting at every step took 306 285 BDF steps and 506 s)
  bool bdf_live = false;
  int reject_streak = 0;  // consecutive rejections of the current step
  constexpr int kMaxRejectStreak = 8;
  auto finish = [&](TvlqrResult::Status st, std::string msg) {
    res.status = st;
    res.message = std::move(msg);
    res.steps = accepted + (bdf ? bdf->steps() : 0);
    res.rhs_evaluations = ex.rhs_evaluations() + (bdf ? bdf->rhs_evaluations() : 0);
    res.linear_iterations = bdf ? bdf->linear_iterations() : 0;
    res.preconditioner_setups = ex.factorizations() + d.setups;
    res.modal_setups = ex.factorizations() - fallbacks + d.modal_setups;
    res.rejected_steps = rejected;
    res.fixed_point_iterations = ex.iterations();
    res.fallback_steps = fallbacks;
  };

  // A model that throws (an LtvSystem's callback) ends the sweep as a failure with the time
  // reached, as in the BDF sweep, instead of escaping solve_tvlqr.
  try {
  // the state at tf, in the frame's coordinates
  Eigen::MatrixXd P = res.Qf / d.sigma, GtP, Pg;
  rotate_P(P, sw.tf, false);
  Eigen::VectorXd s = Eigen::VectorXd::Zero(n), sg;
  double c = 0.0, cg = 0.0;
  int idx = G - 1;
  if (!d.eval(sw.tf)) return finish(TvlqrResult::Status::IntegrationFailed, d.error);
  GtP = d.G.transpose() * P;
  Pg = P;
  sg = s;
  record(idx, GtP, sg, c, &Pg);
  --idx;

  const int pieces = static_cast<int>(sw.bounds.size()) - 1;
  for (int p = pieces - 1; p >= 0; --p) {
    const double a_t = sw.bounds[p], b_t = sw.bounds[p + 1];
    const double tau_a = sw.tf - b_t, tau_b = sw.tf - a_t, len = tau_b - tau_a;
    d.piece_mid_t = 0.5 * (a_t + b_t);
    d.cached = false;
    d.have_pre = false;
    if (!ex.start(tau_a, P, s, c)) return finish(TvlqrResult::Status::IntegrationFailed, d.error);
    // The model may jump at a breakpoint: start small, and within the fastest pole's
    // transient (the nodes would miss it in c, which sees it quadratically; P and s are exact
    // there). At NOA = 20 a first step of 1e-3·len instead left c0 off by 3e-3.
    bdf_live = false;  // a new piece: the model may jump
    double h = 1e-3 * len;
    if (ex.fastest_rate() > 0.0) h = std::min(h, 1.0 / ex.fastest_rate());
    long steps_here = 0;
    while (tau_b - ex.tau() > 1e-13 * span) {
      if (++steps_here > o.max_steps)
        return finish(TvlqrResult::Status::IntegrationFailed,
                      "more than max_steps = " + std::to_string(o.max_steps) + " steps in the piece [" + fmt(a_t) +
                          ", " + fmt(b_t) + "] s (at t = " + fmt(sw.tf - ex.tau()) + " s)");
      const double tau = ex.tau(), left = tau_b - tau;
      const double hh = (h >= 0.999 * left) ? left : h;  // no sliver at the piece's end
      const bool last = hh == left;
      // grid points inside the step (the piece's start a_t exactly at its end)
      std::vector<double> taus;
      std::vector<int> which;
      for (int i = idx; i >= 0 && sw.grid[i] >= a_t; --i) {
        const double tg = sw.grid[i] == a_t ? tau_b : sw.tf - sw.grid[i];
        if (tg > tau + hh && !(last && sw.grid[i] == a_t)) break;
        taus.push_back(last && sw.grid[i] == a_t ? tau + hh : std::min(tg, tau + hh));
        which.push_back(i);
      }
      if (o.budget) {
        if (o.budget->steps_left(step_work) < 1) {
          o.budget->mark_exhausted();
          return finish(TvlqrResult::Status::IntegrationFailed,
                        "stopped at t = " + fmt(sw.tf - tau) + " s: " + o.budget->spent_message());
        }
        o.budget->charge(step_work);
      }
      const ExponentialRiccati::Outcome outcome = ex.step(hh);
      if (outcome == ExponentialRiccati::Outcome::Failed)
        return finish(TvlqrResult::Status::IntegrationFailed, d.error);
      if (outcome == ExponentialRiccati::Outcome::Rejected) {
        ++rejected;
        h = ex.suggested_step();
        // Rejected again and again (an error estimate at a round-off floor, with a form near
        // the condition bound): this step by BDF below rather than steps shrinking to nothing.
        if (++reject_streak < kMaxRejectStreak && h > 1e-14 * span) continue;
      }
      if (outcome == ExponentialRiccati::Outcome::Accepted) {
        ++accepted;
        bdf_live = false;
        reject_streak = 0;
        for (std::size_t k = 0; k < which.size(); ++k) {
          const int i = which[k];
          if (!d.eval(sw.grid[i])) return finish(TvlqrResult::Status::IntegrationFailed, d.error);
          const double theta = std::clamp((taus[k] - tau) / hh, 0.0, 1.0);
          const bool want_P = o.store_riccati || i == 0;
          ex.state_at(theta, d.G, GtP, sg, cg, want_P ? &Pg : nullptr);
          record(i, GtP, sg, cg, want_P ? &Pg : nullptr);
          if (o.progress) o.progress(sw.tf - sw.grid[i]);
        }
        idx -= static_cast<int>(which.size());
        h = ex.suggested_step();
        continue;
      }
      // NoForm (or rejected kMaxRejectStreak times): this step by BDF, from the current state
      reject_streak = 0;
      ++fallbacks;
      Eigen::VectorXd y(nt + n + 1);
      pack(ex.P(), y.data());
      y.segment(nt, n) = ex.s();
      y(nt + n) = ex.c();
      if (!bdf) {
        bdf = std::make_unique<BdfRiccati>(d, o, tau, y.data());
      } else if (!bdf_live) {
        std::copy(y.data(), y.data() + y.size(), bdf->state());
      }
      if (!bdf_live) d.have_pre = false;
      // BDF must reach the step's end even when no grid time lies inside the step
      std::vector<double> stops = taus;
      if (stops.empty() || stops.back() < tau + hh) stops.push_back(tau + hh);
      const std::string failure = bdf->advance(tau, tau + hh, !bdf_live, stops, [&](int k) {
        if (k >= static_cast<int>(which.size())) return true;  // the step's end: nothing to record
        const int i = which[k];
        if (!d.eval(sw.grid[i])) return false;
        const double* yk = bdf->state();
        unpack(yk, n, Pg);
        GtP = d.G.transpose() * Pg;
        sg = Eigen::Map<const Eigen::VectorXd>(yk + nt, n);
        record(i, GtP, sg, yk[nt + n], &Pg);
        if (o.progress) o.progress(sw.tf - sw.grid[i]);
        return true;
      });
      if (!failure.empty()) return finish(TvlqrResult::Status::IntegrationFailed, failure + " (a BDF step of the exponential sweep)");
      idx -= static_cast<int>(which.size());
      const double* ye = bdf->state();
      unpack(ye, n, P);
      if (!ex.start(tau + hh, P, Eigen::Map<const Eigen::VectorXd>(ye + nt, n), ye[nt + n]))
        return finish(TvlqrResult::Status::IntegrationFailed, d.error);
      bdf_live = true;
      // try the exponential form again after twice the span: fewer futile factorizations
      // where the loop keeps no form, one step's work lost where it regains one
      h = std::min(2.0 * hh, len);
    }
    P = ex.P();
    s = ex.s();
    c = ex.c();
  }
  if (idx >= 0)  // every grid time must have its gain (a piece ended without its last step)
    return finish(TvlqrResult::Status::IntegrationFailed,
                  "the exponential sweep left the gains before t = " + fmt(sw.grid[idx]) + " s unset");
  finish(TvlqrResult::Status::Solved, "solved");
  } catch (const std::exception& e) {
    finish(TvlqrResult::Status::IntegrationFailed,
           "the model failed near t = " + fmt(sw.tf - ex.tau()) + " s (exponential sweep): " + e.what());
  }
}

}  // namespace freeflex::detail

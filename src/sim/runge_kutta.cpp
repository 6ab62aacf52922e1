// Explicit embedded Runge-Kutta pairs with step-size control and dense output, behind
// the piece stepper of sim/stepper.hpp (docs/theory.md section 8). Error control and
// step-size choice as Hairer's DOP853: local extrapolation, error weights
// atol_i + rtol max(|y_n,i|, |y_n+1,i|), the new step from err^(-1/(q+1)) with a safety
// factor, changed by a factor within [1/3, 6], not grown right after a rejection.
// Quadratures ride along as extra components outside the error test, so the states are
// the same with or without them.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "sim/rk_tableaus.hpp"
#include "sim/stepper.hpp"
#include "util/avx2_clones.hpp"
#include "util/vec4.hpp"
#include "util/finite.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

std::string fmt(double v) { return util::format_number(v, 12); }

// Step-size control: Hairer's DOP853 takes safety 0.9 and no memory (beta 0); on the paper's
// moment example 0.8 and beta 0.04 (Hairer's value for stabilized control) reached an error
// of 1e-4 rad in θ with 20% fewer right-hand sides at NOA 6 and 16% fewer at NOA 20, since a
// quarter of the steps were rejected at 0.9; Verner's pair did best with them too (7-8%
// fewer than at 0.9 and beta 0; docs/benchmarks.md, explicit Runge-Kutta pairs).
constexpr double kSafety = 0.8;
constexpr double kBeta = 0.04;      ///< the new step also grows with (previous error)^beta
constexpr double kMaxShrink = 3.0;  ///< a step is at least a third of the one before
constexpr double kMaxGrowth = 6.0;  ///< and at most six times it
/// A step one of whose trial stages the model refused (out of its range, not finite,
/// thrown) is rejected and retried ten times shorter: an accepted state is never such a
/// stage, and a solution that does leave the range reaches round-off in a few retries.
constexpr double kFailedStageShrink = 10.0;

/// A linear combination of stages: Σ_t w[t] col[t] (the columns of the stages' matrix
/// whose weights are not zero; most a(i, j) of these pairs' later stages are zero).
struct Combination {
  std::vector<const double*> col;
  std::vector<double> w;
  int terms() const { return static_cast<int>(w.size()); }
};

// The stepper's vector loops (the kernels below) compiled for AVX2 and for the baseline
// (util/avx2_clones.hpp; CMakeLists.txt builds this file with -ffp-contract=off for every
// compiler, so no multiply-add is fused and the bits are the same).
#if defined(__GNUC__)
#define FF_RK_VECTORS 1
// Four doubles as one value (GCC's vector extension: AVX2 registers in the AVX2 clone, two
// SSE2 registers in the baseline); loads and stores through memcpy, no alignment assumed.
// V4 values pass only between always-inlined helpers, so no call's ABI depends on AVX
// (CMakeLists.txt silences GCC's -Wpsabi note for this file).
using util::V4;
FREEFLEX_ALWAYS_INLINE V4 load(const double* p) { return util::load4(p); }
FREEFLEX_ALWAYS_INLINE void store(double* p, V4 v) { util::store4(p, v); }
FREEFLEX_ALWAYS_INLINE V4 splat(double x) { return util::splat4(x); }
#else
#define FF_RK_VECTORS 0
#endif

/// out_r = [start_r +] Σ_t w_t col_t,r for r < N: each entry sums its terms in order
/// (from start_r, or from the first term), the same bits as a loop over the terms per
/// entry, but eight entries at a time with their sums kept in registers across the terms.
template <bool kStart>
FREEFLEX_ALWAYS_INLINE void sum_columns(double* __restrict out, const double* __restrict start, const double* const* col,
                        const double* w, int terms, int N) {
  int r = 0;
#if FF_RK_VECTORS
  for (; r + 8 <= N; r += 8) {
    V4 a0, a1;
    int t = 0;
    if (kStart) {
      a0 = load(start + r), a1 = load(start + r + 4);
    } else {
      a0 = splat(w[0]) * load(col[0] + r), a1 = splat(w[0]) * load(col[0] + r + 4);
      t = 1;
    }
    for (; t < terms; ++t) {
      const V4 v = splat(w[t]);
      a0 += v * load(col[t] + r);
      a1 += v * load(col[t] + r + 4);
    }
    store(out + r, a0);
    store(out + r + 4, a1);
  }
  for (; r + 4 <= N; r += 4) {
    V4 a0;
    int t = 0;
    if (kStart) {
      a0 = load(start + r);
    } else {
      a0 = splat(w[0]) * load(col[0] + r);
      t = 1;
    }
    for (; t < terms; ++t) a0 += splat(w[t]) * load(col[t] + r);
    store(out + r, a0);
  }
#endif
  for (; r < N; ++r) {
    double acc;
    int t = 0;
    if (kStart) {
      acc = start[r];
    } else {
      acc = w[0] * col[0][r];
      t = 1;
    }
    for (; t < terms; ++t) acc += w[t] * col[t][r];
    out[r] = acc;
  }
}

/// s = y + h Σ_t w_t col_t over the N entries: the sum first, as Hairer's code, so that
/// y takes one rounding.
FREEFLEX_AVX2_CLONES void combine_stage(double* __restrict s, const double* __restrict y, const Combination& c, int N,
                                double h) {
  if (c.terms() == 0) {
    for (int r = 0; r < N; ++r) s[r] = y[r];
    return;
  }
  sum_columns<false>(s, nullptr, c.col.data(), c.w.data(), c.terms(), N);
  for (int r = 0; r < N; ++r) s[r] = y[r] + h * s[r];
}

/// s = y + Σ_t hw_t col_t, adding term by term to y (the new solution of a pair without
/// FSAL; hw: the weights times the step).
FREEFLEX_AVX2_CLONES void advance_solution(double* __restrict s, const double* __restrict y, const Combination& c,
                                   const double* hw, int N) {
  sum_columns<true>(s, y, c.col.data(), hw, c.terms(), N);
}

/// e = Σ_t w_t col_t over the first n entries (0 for no terms).
FREEFLEX_AVX2_CLONES void weigh_stages(double* __restrict e, const Combination& c, int n) {
  if (c.terms() == 0) {
    for (int r = 0; r < n; ++r) e[r] = 0.0;
    return;
  }
  sum_columns<false>(e, nullptr, c.col.data(), c.w.data(), c.terms(), n);
}

class RungeKuttaStepper final : public detail::PieceStepper {
 public:
  RungeKuttaStepper(const OdeSystem& system, const IntegratorOptions& options, const detail::ButcherPair& tab)
      : system_(system), options_(options), tab_(tab), n_(system.dim), nq_(system.quadrature_dim) {
    const int N = n_ + nq_;
    out_.setZero(n_);
    quad_out_.setZero(nq_);
    y_.setZero(N);
    y_old_.setZero(N);
    stage_.setZero(N);
    e_sum_.setZero(n_);
    K_.setZero(N, tab_.dense_stages);
    k_next_.setZero(N);
    Q_.setZero(N, tab_.dense.cols());
    if (nq_ > 0) x_quad_.setZero(n_);
    const VariableChange& change = system.variables;
    atol_ = change.active() && change.atol_scale.size() == n_ ? Eigen::VectorXd(options.atol * change.atol_scale)
                                                               : Eigen::VectorXd::Constant(n_, options.atol);
    // the nonzero weights of each combination, with pointers to their columns of K_ (which
    // is not resized after this, and the stepper is neither copied nor moved)
    const auto add = [this](Combination& c, int j, double v) {
      if (v == 0.0) return;
      c.col.push_back(K_.col(j).data());
      c.w.push_back(v);
    };
    rows_.resize(tab_.dense_stages);
    for (int i = 0; i < tab_.dense_stages; ++i)
      for (int j = 0; j < i; ++j) add(rows_[i], j, tab_.a[i][j]);
    for (int i = 0; i < tab_.stages; ++i) add(e_, i, tab_.e[i]);
    for (int i = 0; i < tab_.stages; ++i) add(b_, i, tab_.b[i]);
    for (int i = 0; i < static_cast<int>(tab_.e3.size()); ++i) add(e3_, i, tab_.e3[i]);
    hb_.resize(b_.w.size());
  }
  RungeKuttaStepper(const RungeKuttaStepper&) = delete;  // the combinations point into K_
  RungeKuttaStepper& operator=(const RungeKuttaStepper&) = delete;

  double* state() override { return out_.data(); }
  const double* quadrature() override { return quad_out_.data(); }

  void start(double t0, double piece_mid) override {
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(nq_);
    restart(t0, piece_mid, zero.data());
  }

  void restart(double t, double piece_mid, const double* quad) override {
    y_.head(n_) = out_;
    y_.tail(nq_) = Eigen::Map<const Eigen::VectorXd>(quad, nq_);
    t_ = t;
    piece_mid_ = piece_mid;
    k0_ = K0::Evaluate;   // the new piece's loads: k_0 and the first step are found again
    have_step_ = false;
    h_ = 0.0;
    rejected_ = false;
    stage_failure_.clear();
    err_old_ = 1e-4;
  }

  void stop_time(double b) override { stop_ = b; }

  Outcome advance(double tout, long max_steps, bool budget_binds, WorkBudget* budget, long long step_work) override {
    Outcome out;
    for (long taken = 0;; ++taken) {
      if (tout == t_) {
        out_ = y_.head(n_);
        quad_out_ = y_.tail(nq_);
        break;
      }
      if (have_step_ && tout < t_ && tout >= t_old_) {
        if (interpolate(tout)) break;
        continue;  // the step was taken back (a refused stage of its interpolant): step again
      }
      if (taken >= max_steps) {
        out.message = std::string(tab_.name) + " failed at t = " + fmt(t_) + ": " +
                      (budget_binds ? "the integration's step budget, max_total_steps = " +
                                          std::to_string(options_.max_total_steps) +
                                          ", is spent; the simulated span needs more work than it allows"
                                    : "max_steps = " + std::to_string(options_.max_steps) +
                                          " steps taken in this piece before reaching the next output time; the "
                                          "problem may be stiff (use BDF) or max_steps too small");
        return failed(out, false);
      }
      if (budget && budget->steps_left(step_work) < 1) {
        budget->mark_exhausted();
        out.message = "stopped at t = " + fmt(t_) + ": " + budget->spent_message();
        return failed(out, false);
      }
      if (!step()) return failed(out);
      if (budget) budget->charge(step_work);
    }
    out.reached = tout;
    out.at_stop = tout == stop_ && t_ == stop_;
    return out;
  }

  long steps() const override { return steps_; }
  long rhs_evaluations() const override { return rhs_; }
  const char* name() const override { return tab_.name; }

 private:
  Outcome& failed(Outcome& out, bool with_reason = true) {
    out.ok = false;
    out.reached = t_;
    if (with_reason) out.message = std::string(tab_.name) + " failed at t = " + fmt(t_) + ": " + why_;
    return out;
  }

  /// k = f(t, y) for the augmented state (model, then quadratures); false with why_ set.
  bool eval(double t, const Eigen::VectorXd& y, Eigen::Ref<Eigen::VectorXd> k) {
    ++rhs_;
    const Instant at{t, piece_mid_};
    try {
      if (!system_.rhs(at, y.head(n_), k.head(n_))) {
        why_ = "right-hand side failed at t = " + fmt(t) + ": " + detail::user_message(system_, "right-hand side");
        return false;
      }
      if (!util::all_finite(k.head(n_))) {
        why_ = "right-hand side returned a non-finite derivative at t = " + fmt(t);
        return false;
      }
      if (nq_ > 0) {
        bool ok = false;
        if (system_.variables.active()) {
          system_.variables.to_x(at, y.head(n_), x_quad_);
          ok = system_.quadrature(at, x_quad_, k.tail(nq_));
        } else {
          ok = system_.quadrature(at, y.head(n_), k.tail(nq_));
        }
        if (!ok || !util::all_finite(k.tail(nq_))) {
          why_ = "the quadrature integrand failed or was not finite at t = " + fmt(t);
          return false;
        }
      }
      return true;
    } catch (const std::exception& e) {
      why_ = "right-hand side threw at t = " + fmt(t) + ": " + e.what();
    } catch (...) {
      why_ = "right-hand side threw an unknown exception at t = " + fmt(t);
    }
    return false;
  }

  /// stage_ = y + h Σ_j a(i, j) k_j (combine_stage below).
  void form_stage(const Eigen::VectorXd& y, double h, int i) {
    combine_stage(stage_.data(), y.data(), rows_[i], n_ + nq_, h);
  }

  /// Σ_r (Σ_j w_j k_j,r / sk_r)^2 over the model's components.
  double weighted_sum(const Combination& ws, const Eigen::VectorXd& y_new) const {
    weigh_stages(e_sum_.data(), ws, n_);
    const double* e = e_sum_.data();
    double sum = 0.0;
    for (int r = 0; r < n_; ++r) {
      const double sk = atol_[r] + options_.rtol * std::max(std::abs(y_[r]), std::abs(y_new[r]));
      sum += (e[r] / sk) * (e[r] / sk);
    }
    return sum;
  }

  /// The scaled error of the step just formed (<= 1: accepted).
  double error_norm(double h, const Eigen::VectorXd& y_new) const {
    const double e = weighted_sum(e_, y_new);
    if (e3_.terms() == 0) return std::abs(h) * std::sqrt(e / n_);
    // DOP853: the fifth-order estimate, damped where the third-order one is small
    double den = e + 0.01 * weighted_sum(e3_, y_new);
    if (!(den > 0.0)) den = 1.0;
    return std::abs(h) * e * std::sqrt(1.0 / (n_ * den));
  }

  /// Hairer's starting step (Solving ODE I, II.4): an Euler step to gauge f', then the
  /// step whose leading error term would be 0.01.
  bool initial_step() {
    const int N = n_ + nq_;
    double dnf = 0.0, dny = 0.0;
    for (int r = 0; r < n_; ++r) {
      const double sk = atol_[r] + options_.rtol * std::abs(y_[r]);
      dnf += (K_(r, 0) / sk) * (K_(r, 0) / sk);
      dny += (y_[r] / sk) * (y_[r] / sk);
    }
    double h = dnf <= 1e-10 || dny <= 1e-10 ? 1e-6 : std::sqrt(dny / dnf) * 0.01;
    if (options_.max_step > 0.0) h = std::min(h, options_.max_step);
    h = std::min(h, stop_ - t_);
    for (;;) {  // an Euler trial the model refuses is shortened (as refused stages are in step())
      for (int r = 0; r < N; ++r) stage_[r] = y_[r] + h * K_(r, 0);
      if (eval(t_ + h, stage_, K_.col(1))) break;
      h /= kFailedStageShrink;
      if (!above_round_off(h)) {
        why_ += " (starting steps down to " + fmt(h) + " s, round-off at this t, were all refused)";
        return false;
      }
    }
    double der2 = 0.0;
    for (int r = 0; r < n_; ++r) {
      const double sk = atol_[r] + options_.rtol * std::abs(y_[r]);
      der2 += ((K_(r, 1) - K_(r, 0)) / sk) * ((K_(r, 1) - K_(r, 0)) / sk);
    }
    const double der12 = std::max(std::sqrt(der2) / h, std::sqrt(dnf));
    const double h1 = der12 <= 1e-15 ? std::max(1e-6, h * 1e-3) : std::pow(0.01 / der12, 1.0 / tab_.order);
    h_ = std::min(100.0 * h, h1);
    if (options_.max_step > 0.0) h_ = std::min(h_, options_.max_step);
    return true;
  }

  /// Whether a step h from t_ is above round-off: of t_, or of the piece's span at t_ = 0
  /// (where |t_| eps is 0 and a refused step would be cut down to underflow).
  bool above_round_off(double h) const {
    return 0.1 * h > std::max(std::abs(t_), std::abs(stop_ - t_)) * DBL_EPSILON;
  }

  /// One accepted step towards stop_ (after any rejections); false with why_ set.
  bool step() {
    const int s = tab_.stages;
    switch (k0_) {
      case K0::Evaluate:
        if (!eval(t_, y_, K_.col(0))) return false;  // at an accepted state: the model's range is left
        break;
      case K0::LastStage: K_.col(0) = K_.col(s - 1); break;
      case K0::Next: K_.col(0) = k_next_; break;
      case K0::Current: break;
    }
    k0_ = K0::Current;
    if (h_ == 0.0 && !initial_step()) return false;
    const double expo = 1.0 / (tab_.error_order + 1) - 0.2 * kBeta;  // Hairer's exponent with memory
    for (;;) {
      double h = h_;
      if (options_.max_step > 0.0) h = std::min(h, options_.max_step);
      bool to_stop = false;
      if (t_ + 1.01 * h > stop_) {  // no sliver of a step left before the stop time
        h = stop_ - t_;
        to_stop = true;
      }
      if (!above_round_off(h)) {
        if (!stage_failure_.empty())  // the model refused every shorter trial: the solution leaves it here
          why_ = stage_failure_ + " (steps down to " + fmt(h) + " s, round-off at this t, were all refused)";
        else
          why_ = "the step size fell to " + fmt(h) + " s, round-off at this t: the solution may be singular, the "
                 "right-hand side discontinuous at a time that is not a breakpoint, or the problem stiff (use BDF)";
        return false;
      }
      bool refused = false;
      for (int i = 1; i < s && !refused; ++i) {
        form_stage(y_, h, i);
        refused = !eval(t_ + tab_.c[i] * h, stage_, K_.col(i));
      }
      if (refused) {
        // A trial stage of too long a step can leave the model's range (the mass matrix of
        // the full model in modal variables, just after a restart) where the solution does
        // not: reject the step, as Hairer's codes do with a non-finite error.
        reject_refused(h);
        continue;
      }
      // with FSAL the last stage was formed at y_n+1; else form it from b
      if (!tab_.fsal) {
        for (int t = 0; t < b_.terms(); ++t) hb_[t] = h * b_.w[t];
        advance_solution(stage_.data(), y_.data(), b_, hb_.data(), n_ + nq_);
      }
      const double err = error_norm(h, stage_);
      // A pair without FSAL evaluates its new point now, not at the next step: a point the
      // model refuses is a rejected step, not the end of the run (the value is the next
      // step's k_0, so this costs nothing; at a piece's end the next piece evaluates anew).
      if (err <= 1.0 && !tab_.fsal && !to_stop && !eval(t_ + h, stage_, k_next_)) {
        reject_refused(h);
        continue;
      }
      if (err <= 1.0) {
        double grow = err > 0.0 ? kSafety * std::pow(err, -expo) * std::pow(err_old_, kBeta) : kMaxGrowth;
        err_old_ = std::max(err, 1e-4);
        grow = std::min(kMaxGrowth, std::max(1.0 / kMaxShrink, grow));
        if (rejected_) grow = std::min(grow, 1.0);
        rejected_ = false;
        stage_failure_.clear();
        y_old_.swap(y_);
        y_ = stage_;
        t_old_ = t_;
        t_ = to_stop ? stop_ : t_ + h;
        h_step_ = h;
        h_ = h * grow;
        have_step_ = true;
        dense_ready_ = false;
        k0_ = tab_.fsal ? K0::LastStage : to_stop ? K0::Evaluate : K0::Next;
        ++steps_;
        return true;
      }
      // rejected (a non-finite error too: the step shrinks until it is too small)
      stage_failure_.clear();  // this trial's stages were all taken: the model refused none
      const double shrink = std::isfinite(err) ? std::min(kMaxShrink, std::pow(err, expo) / kSafety) : kMaxShrink;
      h_ = h / shrink;
      rejected_ = true;
    }
  }

  /// out_, quad_out_ = y(tout) on the last step, from its dense output. False with the
  /// step taken back when the model refuses one of the interpolant's extra stages.
  bool interpolate(double tout) {
    const int N = n_ + nq_;
    if (!dense_ready_) {
      for (int i = tab_.stages; i < tab_.dense_stages; ++i) {
        form_stage(y_old_, h_step_, i);
        if (!eval(t_old_ + tab_.c[i] * h_step_, stage_, K_.col(i))) {
          take_back_step();
          return false;
        }
      }
      Q_.noalias() = K_ * tab_.dense;
      dense_ready_ = true;
    }
    const double theta = (tout - t_old_) / h_step_;
    const int deg = static_cast<int>(Q_.cols());
    for (int r = 0; r < N; ++r) {
      double p = 0.0;
      for (int j = deg - 1; j >= 0; --j) p = (p + Q_(r, j)) * theta;
      const double v = y_old_[r] + h_step_ * p;
      if (r < n_)
        out_[r] = v;
      else
        quad_out_[r - n_] = v;
    }
    return true;
  }

  /// A step of length h one of whose trial states the model refused (why_ says why) is
  /// rejected and the next trial is ten times shorter.
  void reject_refused(double h) {
    stage_failure_ = why_;
    h_ = h / kFailedStageShrink;
    rejected_ = true;
  }

  /// Undoes the last accepted step, whose dense output the model refused: a trial state of
  /// it, like a refused stage (step()), so the step is retried ten times shorter. K_'s
  /// first column still holds f at the step's start, which is the state again.
  void take_back_step() {
    y_.swap(y_old_);
    t_ = t_old_;
    reject_refused(h_step_);
    have_step_ = false;
    dense_ready_ = false;
    k0_ = K0::Current;
    --steps_;
  }

  const OdeSystem& system_;
  const IntegratorOptions& options_;
  const detail::ButcherPair& tab_;
  const int n_, nq_;
  std::vector<Combination> rows_;  ///< of the stages: y + h (row i) is stage i's argument
  Combination e_, e3_, b_;         ///< the error estimates, the solution
  std::vector<double> hb_;         ///< scratch: b_'s weights times the step
  Eigen::VectorXd atol_;
  Eigen::VectorXd out_, quad_out_;  ///< the state at the time last reached, as the driver reads it
  Eigen::VectorXd y_, y_old_, stage_, x_quad_;
  Eigen::MatrixXd K_, Q_;           ///< stages (columns); dense output's coefficients
  mutable Eigen::VectorXd e_sum_;   ///< scratch of weighted_sum
  double t_ = 0.0, t_old_ = 0.0, stop_ = 0.0, piece_mid_ = 0.0;
  double h_ = 0.0;       ///< the next step to try (0: to be chosen)
  double h_step_ = 0.0;  ///< of the last accepted step, [t_old_, t_]
  /// Where the next step's k_0 = f(t_, y_) comes from: evaluated, already in K_'s first
  /// column, the last stage (FSAL), or k_next_ (evaluated before the step was accepted).
  enum class K0 { Evaluate, Current, LastStage, Next };
  K0 k0_ = K0::Evaluate;
  Eigen::VectorXd k_next_;  ///< f at the new point of a pair without FSAL
  bool have_step_ = false, dense_ready_ = false, rejected_ = false;
  long steps_ = 0, rhs_ = 0;
  std::string why_;
  std::string stage_failure_;  ///< why the model refused the latest trial step (empty: it did not)
  double err_old_ = 1e-4;  ///< of the last accepted step (Hairer's facold)
};

}  // namespace

std::unique_ptr<detail::PieceStepper> detail::runge_kutta_stepper(const OdeSystem& system,
                                                                  const IntegratorOptions& options) {
  return std::make_unique<RungeKuttaStepper>(
      system, options, options.method == IntegratorOptions::Method::Verner98 ? detail::verner98() : detail::dop853());
}

}  // namespace freeflex

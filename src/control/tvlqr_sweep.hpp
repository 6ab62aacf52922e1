#pragma once
// The backward sweeps of the TV-LQR (control/tvlqr.hpp), private to src/: what
// solve_tvlqr prepares for them (pieces, output grid, terminal weight, the shared model
// data), the BDF sweep (CVODES, control/tvlqr_bdf.cpp) and the exponential one
// (control/tvlqr_exponential.cpp), which takes a step by BDF where it has no
// block-diagonal form of the closed loop.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "control/riccati_flow.hpp"
#include "freeflex/control/tvlqr.hpp"
#include "sim/cvodes.hpp"

namespace freeflex::detail {

/// An orthogonal change of coordinates x = T(t) x_b that rotates each coordinate pair
/// (i, i + 1), i in `pairs`, by the angle θ(t): the first-order model's displacement and
/// velocity of o are inertial, its dynamics body-fixed, so in these coordinates A varies
/// only with θ0', θ0'' and the exponential steps can be long (docs/theory.md §12).
struct RotatingFrame {
  std::vector<int> pairs;
  std::function<void(const Instant&, double& angle, double& rate)> angle;
};

/// A problem prepared by solve_tvlqr (arguments validated, result sized).
struct Sweep {
  LtvEvaluator* model = nullptr;
  int n = 0, m = 0;
  double t0 = 0.0, tf = 0.0;
  std::vector<double> bounds;  ///< t0 < ... < tf: the pieces between the model's breakpoints
  std::vector<double> grid;    ///< output times, ascending; every bound is one
  Eigen::MatrixXd Q, R;        ///< symmetrized
  const TvlqrOptions* options = nullptr;
  const RotatingFrame* frame = nullptr;  ///< only the exponential sweep uses it
  TvlqrResult* result = nullptr;         ///< t, K, feedforward, P sized; Qf set
};

/// The shared model data of both sweeps for `sw` (σ, Q/σ, R's factor).
void init_riccati_data(const Sweep& sw, LtvEvaluator* model, RiccatiData& d);

/// Fills K, feedforward (and P, P0, s0, c0) at grid index idx from the packed σ-scaled
/// state y (the BDF sweep's); d.eval(grid time) must have succeeded.
void record_packed(const Sweep& sw, RiccatiData& d, int idx, const double* y);

/// CVODES BDF on the packed state [P̂ upper triangle, ŝ, ĉ] with the frozen-closed-loop
/// Newton solves (control/riccati_flow.hpp).
class BdfRiccati {
 public:
  BdfRiccati(RiccatiData& d, const TvlqrOptions& o, double tau0, const double* y0);
  double* state() { return cv_.state(); }
  /// From the state at tau_a to tau_b (one piece, d.piece_mid_t set), stopping at each
  /// of `taus` (ascending, in (tau_a, tau_b]; the last may be tau_b) and calling out(k)
  /// there. `restart`: reinitialize at tau_a (a new piece or a new starting state). ""
  /// or the reason of the failure, with the time it happened.
  std::string advance(double tau_a, double tau_b, bool restart, const std::vector<double>& taus,
                      const std::function<bool(int)>& out);
  long steps() const { return steps_; }
  long rhs_evaluations() const { return rhs_; }
  long linear_iterations() const { return lin_; }

 private:
  RiccatiData& d_;
  cvodes::Integrator cv_;
  std::unique_ptr<DirectSolverContent> direct_;
  WorkBudget* budget_;  // TvlqrOptions::budget, charged riccati_step_work a step; may be null
  long long work_;
  long max_steps_;
  long steps_ = 0, rhs_ = 0, lin_ = 0;
};

/// The two sweeps: fill `*sw.result` (status, message, law, counters).
void sweep_bdf(const Sweep& sw);
void sweep_exponential(const Sweep& sw);

}  // namespace freeflex::detail

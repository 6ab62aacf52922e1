#pragma once
// What [lqg] and [sweep] share (the law's plant and nominal, the filter, the metric
// targets) and what the command line makes of their results. Private to src/.
#include <memory>

#include <nlohmann/json.hpp>

#include "app/run_output.hpp"
#include "freeflex/app/sweep.hpp"

namespace freeflex::detail {

/// The nominal body, loads, u0 and first-order model the [controller]'s law was designed
/// on (the model refers to body and nominal: a Flight is not copied).
struct Flight {
  Flight(const Design& design, const SuppressionStudyResult& suppression, const ManeuverStudyResult* maneuver);
  Flight(const Flight&) = delete;
  Flight& operator=(const Flight&) = delete;
  FlexibleBody body;
  Excitation loads;
  ActuatorCommandFunction u0;
  std::shared_ptr<const RigidTrajectory> nominal;
  std::unique_ptr<FirstOrderModel> model;
};

/// The [lqg] filter of the design's sensors on the nominal first-order model; its
/// discretization is charged to `budget`.
KalmanResult design_filter(const Design& design, const Flight& flight, std::shared_ptr<WorkBudget> budget);
/// Residual energy of the [controller] study's main chain case NAME ("open_loop",
/// "tvlqr") on the full model; 0 when absent.
double main_chain_energy(const SuppressionStudyResult& suppression, const std::string& name);
/// The digital TV-LQR (solve_discrete_tvlqr) of the [controller]'s weights over its
/// horizon at `rate`, terminal weight the continuous law's; `model` is reused when it is
/// the discretization over that horizon at that rate, else one is made, charged to `budget`.
TvlqrResult design_digital_law(const Design& design, const Flight& flight, const TvlqrResult& continuous, double rate,
                               std::shared_ptr<WorkBudget> budget, const DiscreteLtv* model = nullptr);
/// The rigid targets of the metrics: the nominal motion at the end of the runs.
MetricTargets targets(const Design& design, const Flight& flight);

void write_lqg(const Design& design, const LqgStudyResult& r, RunOutput& out);
nlohmann::ordered_json to_json(const Design& design, const LqgStudyResult& r);
void write_sweep(const Design& design, const SweepStudyResult& r, RunOutput& out);
nlohmann::ordered_json to_json(const Design& design, const SweepStudyResult& r);

}  // namespace freeflex::detail

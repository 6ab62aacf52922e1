#pragma once
// What the command line makes of each study's result: its files (CSV tables, figures)
// through the run's output, and its entry in summary.json. Private to src/.
#include <nlohmann/json.hpp>

#include "app/run_output.hpp"
#include "freeflex/app/studies.hpp"

namespace freeflex::detail {

using Json = nlohmann::ordered_json;

/// A vector as a JSON array (non-finite entries become null when dumped).
Json json_array(const Eigen::VectorXd& v);
/// "ok" when the result is ok, else its status name or reason.
template <class R>
std::string status_text(const R& r) {
  return r.ok() ? "ok" : to_string(r.status);
}

/// A residual vibration energy flown again at 10x tighter tolerances is not converged
/// when it moved by more than a tenth of itself and by more than `floor` (1e-10 of the
/// open loop's energy: below it an energy is zero to the integrations' accuracy).
inline bool energy_not_converged(double change_J, double energy_J, double floor_J) {
  return change_J > 0.1 * energy_J && change_J > floor_J;
}

/// Figures leave out a coordinate whose largest excursion is at most this: one that
/// never moves (R_x, R_y of a pure rotation) would be a flat panel at zero.
inline constexpr double kMovingCoordinate = 1e-9;
/// Whether a coordinate's history moves (see kMovingCoordinate).
inline bool moves(const Eigen::Ref<const Eigen::VectorXd>& history) {
  return history.size() > 0 && history.cwiseAbs().maxCoeff() > kMovingCoordinate;
}

void write_free_vibration(const Design& design, const FreeVibrationStudyResult& r, RunOutput& out);
Json to_json(const Design& design, const FreeVibrationStudyResult& r);

void write_maneuver(const Design& design, const ManeuverStudyResult& r, RunOutput& out);
Json to_json(const ManeuverStudyResult& r);

void write_simulation(const Design& design, const SimulationStudyResult& r, RunOutput& out);
Json to_json(const SimulationStudyResult& r);

void write_suppression(const Design& design, const SuppressionStudyResult& r, RunOutput& out);
/// [export]: NAME.mat and NAME_*.csv (nothing without [export]).
void write_export(const Design& design, const SuppressionStudyResult& r, RunOutput& out);
/// Empty (null) when the study has no entry (its open loop failed: the run's message says why).
Json to_json(const Design& design, const SuppressionStudyResult& r);

}  // namespace freeflex::detail

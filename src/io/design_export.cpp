// [export]: which of the controller study's data leave the workbench, in which formats,
// under which file stem (README, design keys and outputs).
#include <algorithm>
#include <cmath>

#include "io/design_sections.hpp"

namespace freeflex::io_detail {

void read_export(Section& root, Design& d, Outputs& outputs) {
  Section s = root.table("export");
  if (!s.present()) return;
  ExportRequest e;
  if (auto name = s.string("name", false, true)) e.name = *name;
  const std::vector<std::string> formats = {"csv", "mat"};
  if (auto f = s.string_array("formats", false)) {
    e.csv = e.mat = false;
    for (const auto& x : *f) {
      if (x == "csv") e.csv = true;
      else if (x == "mat") e.mat = true;
      else s.problem("formats", s.key_path("formats") + ": \"" + x + "\" is not a format; expected \"csv\" or \"mat\"");
    }
  }
  if (auto c = s.string_array("contents", false)) {
    e.gains = e.nominal = e.model = e.poles = e.histories = false;
    for (const auto& x : *c) {
      if (x == "gains") e.gains = true;
      else if (x == "nominal") e.nominal = true;
      else if (x == "model") e.model = true;
      else if (x == "poles") e.poles = true;
      else if (x == "histories") e.histories = true;
      else
        s.problem("contents", s.key_path("contents") + ": \"" + x +
                                  "\" is not exported; expected \"gains\", \"nominal\", \"model\", \"poles\" or "
                                  "\"histories\"");
    }
  }
  auto step = s.number("model_step_s", kTime, false);
  e.model_step_s = step.value_or(0.0);
  s.finish();
  if (!d.controller) {
    s.problem("name", "[export] exports the controller study's data: add a [controller]");
    return;
  }
  const double step_used = e.model_step_s > 0.0 ? e.model_step_s : d.controller->grid_step_s;
  const double span = std::max(d.controller->horizon_s, d.controller->simulate_until_s);
  const bool points_ok =
      !step || check_count(s, "model_step_s", s.key_path("model_step_s") + " = " + shortest(step_used),
                           "controller.horizon_s / simulate_until_s = " + shortest(span), span, step_used,
                           "model grid points", lim::kMaxOutputRows, "raise model_step_s");
  if (points_ok && !d.controller->actuators.empty()) {
    // the model grid (with the gains' grid merged in) holds A, B, g, x0, u0 and both poles
    const ControllerStudy& c = *d.controller;
    const double n = 2.0 * (3 + d.noa), m = static_cast<double>(c.actuators.size());
    const double points = std::ceil(span / step_used - 1e-9) + 1.0 + std::ceil(c.horizon_s / c.grid_step_s - 1e-9) + 1.0;
    const double doubles = points * (n * n + n * (m + 6.0) + m);
    const std::string key = step ? "model_step_s" : s.has("contents") ? "contents" : "name";
    const std::string lead = "export: the model grid of up to " + show_count(points) + " points (model_step_s = " +
                             shortest(step_used) + " over " + shortest(span) + " s and the gains' grid_step_s = " +
                             shortest(c.grid_step_s) + " over horizon_s = " + shortest(c.horizon_s) + ") at noa = " +
                             std::to_string(d.noa) + " (" + shortest(n) + " states)";
    if (doubles > lim::kMaxGainStorage)
      s.problem(key, lead + " keeps " + show_count(std::ceil(doubles)) + " doubles (A, B, g, x0, u0, poles); at most " +
                         shortest(lim::kMaxGainStorage) + " (400 MB): raise model_step_s or grid_step_s, or lower noa");
    else if (e.poles && points * n * n * n > lim::kMaxPolesWork)
      s.problem(key, lead + " asks for 2 eigenvalue problems of " + shortest(n) + " x " + shortest(n) +
                         " at each point: points x n³ = " + show_count(points * n * n * n) + "; at most " +
                         shortest(lim::kMaxPolesWork) + " (about 30 s of CPU): raise model_step_s or leave out "
                         "\"poles\"");
  }
  std::vector<std::string> files;
  if (e.mat) files.push_back(".mat");
  if (e.csv) {
    if (e.gains) files.push_back("_gains.csv");
    if (e.nominal) files.push_back("_nominal.csv");
    if (e.model) files.push_back("_model.csv");
    if (e.poles) files.push_back("_poles.csv");
    if (e.histories)
      for (const char* c : {"open_loop", "tvlqr"})
        for (const char* m : {"first_order", "nonlinear"})
          files.push_back(std::string("_history_") + c + "_" + m + ".csv");
    if (e.histories && d.bang_bang)
      for (int k : d.bang_bang->modes)
        for (const char* m : {"first_order", "nonlinear"})
          files.push_back("_history_bang_bang_k" + std::to_string(k) + "_" + m + ".csv");
  }
  outputs.named(s, "name", e.name, files);
  d.exports = e;
}

}  // namespace freeflex::io_detail

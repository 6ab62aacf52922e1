// [free_vibration]: the NOA sweep of the frequency table and the mode shapes to export.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "freeflex/model/basis.hpp"

#include "io/design_sections.hpp"

namespace freeflex::io_detail {
namespace {

/// Element-modes (elements x (modes + 2)) of the element models the study solves on the
/// finite-element basis (as run_free_vibration_study and mode_table build them).
double basis_work(const Design& d, const FreeVibrationStudy& fv) {
  const FiniteElementOptions& fe = d.basis.finite_element;
  const double pieces = static_cast<double>(d.beam.segments.size() + d.beam.point_masses.size());
  const double E = std::max(static_cast<double>(fe.elements), pieces + 2.0);  // raised to one per interval
  auto build = [](double elements, double modes) { return elements * (modes + 2.0); };
  const bool estimate = !d.beam.plain_uniform();  // exact modes: no error estimate (has_exact_modes)
  const bool clamped = fe.modes == FiniteElementOptions::Modes::ClampedAtReference;
  double work = 0.0;
  const std::vector<int> sweep = fv.noa_sweep.empty() ? std::vector<int>{d.noa} : fv.noa_sweep;
  for (int n : sweep) {
    work += build(E, n);
    if (!estimate) continue;
    if (clamped) work += build(E, 2.0 * n) + build(E, n / 2.0);  // the change to 2n (or from n/2)
    else work += 2 * fe.elements <= kMaxElements ? build(2.0 * E, n) : build(E / 2.0, n);  // Richardson
  }
  for (const auto& m : fv.mode_shapes) work += build(E, m.noa);
  if (!fv.spin_rates.empty()) work += build(E, d.noa);
  return work;
}

}  // namespace

void read_free_vibration(Section& root, Design& d, Outputs& outputs) {
  Section s = root.table("free_vibration");
  if (!s.present()) return;
  FreeVibrationStudy fv;
  // noa: functions of the paper's basis, or modes kept from the finite-element model
  const int most = max_modes(d);
  if (auto v = s.integer_array("noa_sweep", 1, most, false)) {
    if (v->size() > static_cast<std::size_t>(lim::kMaxNoaSweep))
      s.problem("noa_sweep", s.key_path("noa_sweep") + " has " + std::to_string(v->size()) + " entries; at most " +
                                 std::to_string(lim::kMaxNoaSweep) + " (each is a row block of the table)");
    else
      fv.noa_sweep.assign(v->begin(), v->end());
  }
  fv.modes = static_cast<int>(s.integer("modes", 1, kMaxNoa, false).value_or(fv.modes));
  fv.paper_table = s.boolean("paper_table", false).value_or(fv.paper_table);
  fv.table_name = s.string("table_name", false, true).value_or(fv.table_name);
  outputs.named(s, "table_name", fv.table_name, {".csv"});
  // each spin rate is two generalized eigenproblems of the model's size: bounded as noa_sweep
  constexpr std::size_t kMaxSpinRates = lim::kMaxNoaSweep;
  if (auto v = s.number_array("spin_rates_deg_s", Range::nonnegative().supported(-kInf, lim::kMaxRate_deg_s), false)) {
    if (v->size() > kMaxSpinRates)
      s.problem("spin_rates_deg_s", s.key_path("spin_rates_deg_s") + " has " + std::to_string(v->size()) +
                                        " entries; at most " + std::to_string(kMaxSpinRates) +
                                        " (each is a row block of the spinning table)");
    else
      for (double w : *v) fv.spin_rates.push_back(w * M_PI / 180.0);
  }
  fv.spinning_table_name = s.string("spinning_table_name", false, true).value_or(fv.spinning_table_name);
  if (!fv.spin_rates.empty()) outputs.named(s, "spinning_table_name", fv.spinning_table_name, {".csv"});
  std::vector<Section> shapes = s.table_array("mode_shape");
  if (shapes.size() > static_cast<std::size_t>(lim::kMaxModeShapes)) {
    s.problem("mode_shape", "free_vibration.mode_shape: " + std::to_string(shapes.size()) + " tables; at most " +
                                std::to_string(lim::kMaxModeShapes) + " (each writes three files)");
    shapes.clear();
  }
  double rows = 0;  // of all mode shapes
  for (auto& m : shapes) {
    ModeShapeRequest r;
    auto name = m.string("name", true, true);
    r.noa = static_cast<int>(m.integer("noa", 1, most, false).value_or(d.noa));
    auto mode = m.integer("mode", 1, r.noa, true);
    r.points = static_cast<int>(m.integer("points", 2, lim::kMaxModeShapePoints, false).value_or(r.points));
    rows += r.points;
    m.finish();
    if (name) outputs.named(m, "name", *name, {".csv", ".gp", ".png"});
    if (name && mode) {
      r.name = *name;
      r.mode = static_cast<int>(*mode);
      fv.mode_shapes.push_back(r);
    }
  }
  if (rows > lim::kMaxModeShapeRows)
    s.problem("mode_shape", "free_vibration.mode_shape: the " + std::to_string(shapes.size()) +
                                " mode shapes' points add up to " + std::to_string(static_cast<long long>(rows)) +
                                " rows; at most " + std::to_string(static_cast<long long>(lim::kMaxModeShapeRows)) +
                                ": give fewer points or fewer mode shapes");
  s.finish();
  if (d.basis.kind == BasisOptions::Kind::FiniteElement) {
    const double work = basis_work(d, fv);
    if (work > lim::kMaxBasisWork) {
      const std::string key = s.has("noa_sweep") ? "noa_sweep" : !shapes.empty() ? "mode_shape" : "spin_rates_deg_s";
      s.problem(key, "free_vibration: the NOA sweep (with the error estimates' second models), mode shapes and spin "
                     "rates solve element models of " + show_count(work) + " element-modes together (elements x (modes + 2) "
                     "each, model.elements = " + std::to_string(d.basis.finite_element.elements) + "); at most " +
                     shortest(lim::kMaxBasisWork) + " (about 2 min of CPU): fewer NOA values or mode shapes, or "
                     "fewer elements");
    }
  }
  d.free_vibration = fv;
}


}  // namespace freeflex::io_detail

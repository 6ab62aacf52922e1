// [lqg] and [sweep] files: the cases' table, histories and figure; one CSV row per sweep
// sample, the histogram of the residual energies, and their summary.json entries.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <sstream>

#include "app/study_files.hpp"
#include "app/sweep_files.hpp"
#include "freeflex/io/plot.hpp"

namespace freeflex::detail {
namespace {

std::string cell(double v) {
  if (std::isnan(v)) return "";
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

Json metrics_json(const ResponseMetrics& m) {
  Json j = Json::object();
  j["residual_vibration_energy_J"] = m.residual_vibration_energy_J;
  j["mean_vibration_energy_J"] = m.mean_vibration_energy_J;
  j["peak_tip_deflection_m"] = m.peak_tip_deflection_m;
  j["final_position_error_m"] = m.final_position_error_m;
  j["final_attitude_error_rad"] = m.final_attitude_error_rad;
  j["control_effort_N2s"] = m.control_effort;
  j["peak_command"] = m.peak_command;
  return j;
}

}  // namespace

void write_lqg(const Design& design, const LqgStudyResult& r, RunOutput& out) {
  const LqgStudy& lq = *design.lqg;
  if (r.cases.empty()) return;
  std::ostringstream csv;
  csv << "case,residual_vibration_energy_J,mean_vibration_energy_J,peak_tip_deflection_m,final_position_error_m,"
         "final_attitude_error_rad,control_effort_N2s,peak_command\n";
  for (const auto& c : r.cases) {
    const ResponseMetrics& m = c.metrics;
    csv << c.name << ',' << cell(m.residual_vibration_energy_J) << ',' << cell(m.mean_vibration_energy_J) << ','
        << cell(m.peak_tip_deflection_m) << ',' << cell(m.final_position_error_m) << ','
        << cell(m.final_attitude_error_rad) << ',' << cell(m.control_effort) << ',' << cell(m.peak_command) << '\n';
  }
  out.write(lq.table + ".csv", csv.str());
  // histories: right-tip deflection, vibration energy and the computed commands of each case
  const FlexibleBody body = design.body();
  const Eigen::RowVectorXd phi_r = body.basis().value(body.beam().x_right());
  const int N = body.dofs(), n = body.n();
  const Eigen::VectorXd& t = r.cases.front().run.t;
  const ControllerStudy& st = *design.controller;
  const int m = static_cast<int>(st.actuator_names.size());
  std::vector<std::string> header{"t_s"};
  Eigen::MatrixXd h(t.size(), 1 + (2 + m) * static_cast<int>(r.cases.size()));
  h.col(0) = t;
  int col = 1;
  for (const auto& c : r.cases) {
    header.push_back("tip_" + c.name + "_m");
    header.push_back("E_vib_" + c.name + "_J");
    for (int i = 0; i < t.size(); ++i) {
      const bool have = i < c.run.t.size();
      h(i, col) = have ? (phi_r * c.run.z.row(i).segment(3, n).transpose())(0) : std::nan("");
      h(i, col + 1) = have ? body.vibration_energy(c.run.z.row(i).segment(3, n).transpose(),
                                                   c.run.z_dot.row(i).segment(3, n).transpose())
                           : std::nan("");
    }
    col += 2;
  }
  for (const auto& c : r.cases)
    for (int a = 0; a < m; ++a) {
      header.push_back("u_" + c.name + "_" + st.actuator_names[static_cast<std::size_t>(a)]);
      for (int i = 0; i < t.size(); ++i)
        h(i, col) = i < c.run.commands.rows() && a < c.run.commands.cols() ? c.run.commands(i, a) : std::nan("");
      ++col;
    }
  (void)N;
  const std::string hist = lq.table + "_history.csv";
  out.csv(hist, header, h);
  PlotSpec fig{lq.figure, "Sampled TV-LQR (exact state) and LQG (sensors + Kalman filter): " + design.title,
               {{"tip deflection (right end)", "t [s]", "deflection [m]", {}},
                {"vibration energy", "t [s]", "E_vib [J]", {}, true},
                {"commands u0 + u1 as computed (before the actuators' gain, delay and lag; dotted: the limits)",
                 "t [s]", "command [N or N m]", {}}}};
  col = 2;
  std::size_t k = 0;
  for (const auto& c : r.cases) {
    const std::string colour = series_color(k++);
    fig.panels[0].series.push_back({hist, 1, col, c.name, "lines", true, colour});
    fig.panels[1].series.push_back({hist, 1, col + 1, c.name, "lines", true, colour});
    col += 2;
  }
  k = 0;
  for (const auto& c : r.cases) {
    const std::string colour = series_color(k++);
    for (int a = 0; a < m; ++a)  // one colour per case, one dash per actuator
      fig.panels[2].series.push_back({hist, 1, col++, c.name + ": " + st.actuator_names[static_cast<std::size_t>(a)],
                                      a == 0 ? "lines" : "lines dt " + std::to_string(1 + a), true, colour});
  }
  for (int a = 0; a < static_cast<int>(st.limits.size()); ++a) {
    auto& lines = fig.panels[2].hlines;
    if (std::isfinite(st.limits(a)) && std::find(lines.begin(), lines.end(), st.limits(a)) == lines.end()) {
      lines.push_back(st.limits(a));
      lines.push_back(-st.limits(a));
    }
  }
  fig.panels[2].hline_title = "command limits";
  out.plot(fig, design.plots);
}

Json to_json(const Design& design, const LqgStudyResult& r) {
  const LqgStudy& lq = *design.lqg;
  Json j = Json::object();
  j["status"] = r.ok() ? "ok" : r.message;
  j["work_units"] = r.work_units;  // of the study's budget (README, the "(limits)" row)
  j["work_budget_units"] = r.work_budget_units;
  j["sample_rate_hz"] = lq.sample_rate_hz;
  Json sensors = Json::array();
  for (const Sensor& s : design.sensors) sensors.push_back(s.name + " (" + to_string(s.type) + ")");
  j["sensors"] = sensors;
  j["actuator_gain"] = lq.plant.actuator_gain;
  j["lag_s"] = lq.plant.lag_s;
  j["delay_s"] = lq.plant.delay_s;
  j["delay_known"] = lq.delay_known;
  j["seed"] = lq.plant.seed;
  j["kalman_status"] = to_string(r.filter.status);
  j["final_elastic_std"] = json_array(r.final_elastic_std);
  j["open_loop_residual_vibration_energy_J"] = r.open_loop_energy_J;
  j["tvlqr_continuous_residual_vibration_energy_J"] = r.continuous_energy_J;
  Json cases = Json::object();
  for (const auto& c : r.cases) {
    Json e = metrics_json(c.metrics);
    // the change at 10x tighter tolerances ([lqg] error_estimate)
    if (std::isfinite(c.energy_error_estimate_J)) e["residual_vibration_energy_error_estimate_J"] = c.energy_error_estimate_J;
    e["wall_time_s"] = c.run.wall_time_s;
    cases[c.name] = e;
  }
  j["cases"] = cases;
  return j;
}

void write_sweep(const Design& design, const SweepStudyResult& r, RunOutput& out) {
  const SweepStudy& sw = *design.sweep;
  if (r.samples.empty()) return;
  std::vector<std::string> header{"sample"};
  for (const auto& p : r.parameter_names) header.push_back(p);
  for (const char* h : {"ok", "residual_vibration_energy_J", "mean_vibration_energy_J", "peak_tip_deflection_m",
                        "final_attitude_error_rad", "final_position_error_m", "peak_command", "meets_requirement"})
    header.push_back(h);
  const int P = static_cast<int>(r.parameter_names.size());
  Eigen::MatrixXd t(static_cast<Eigen::Index>(r.samples.size()), static_cast<Eigen::Index>(header.size()));
  for (std::size_t i = 0; i < r.samples.size(); ++i) {
    const SweepSample& s = r.samples[i];
    const Eigen::Index row = static_cast<Eigen::Index>(i);
    t(row, 0) = static_cast<double>(s.index);
    for (int k = 0; k < P; ++k) t(row, 1 + k) = k < static_cast<int>(s.values.size()) ? s.values[k] : std::nan("");
    const ResponseMetrics& m = s.metrics;
    const double nan = std::nan("");
    int c = 1 + P;
    t(row, c++) = s.ok ? 1.0 : 0.0;
    t(row, c++) = s.ok ? m.residual_vibration_energy_J : nan;
    t(row, c++) = s.ok ? m.mean_vibration_energy_J : nan;
    t(row, c++) = s.ok ? m.peak_tip_deflection_m : nan;
    t(row, c++) = s.ok ? m.final_attitude_error_rad : nan;
    t(row, c++) = s.ok ? m.final_position_error_m : nan;
    t(row, c++) = s.ok ? m.peak_command : nan;
    t(row, c++) = s.ok && m.residual_vibration_energy_J <= sw.requirement_energy_J ? 1.0 : 0.0;
  }
  out.csv(sw.table + ".csv", header, t);
  // histogram of log10 residual energy, 4 bins per decade
  std::map<long, long> bins;
  for (const SweepSample& s : r.samples)
    if (s.ok && s.metrics.residual_vibration_energy_J > 0.0)
      ++bins[static_cast<long>(std::floor(4.0 * std::log10(s.metrics.residual_vibration_energy_J)))];
  if (bins.empty()) return;
  Eigen::MatrixXd h(static_cast<Eigen::Index>(bins.rbegin()->first - bins.begin()->first + 1), 2);
  for (long b = bins.begin()->first, i = 0; b <= bins.rbegin()->first; ++b, ++i) {
    h(i, 0) = (static_cast<double>(b) + 0.5) / 4.0;
    h(i, 1) = bins.count(b) ? static_cast<double>(bins[b]) : 0.0;
  }
  const std::string counts = sw.figure + "_counts.csv";
  out.csv(counts, {"log10_residual_vibration_energy_J", "samples"}, h);
  Eigen::MatrixXd req(2, 2);
  req << std::log10(sw.requirement_energy_J), 0.0, std::log10(sw.requirement_energy_J), h.col(1).maxCoeff();
  PlotSpec fig{sw.figure, "Sweep of " + std::to_string(r.samples.size()) + " samples: " + design.title,
               {{"residual vibration energy (requirement: log10 E = " + cell(std::log10(sw.requirement_energy_J)) + ")",
                 "log10 E_vib(end) [J]", "samples", {{counts, 1, 2, "samples", "boxes"}}}}};
  fig.panels[0].x_to_data = false;  // bars: room for the outer ones
  out.plot(fig, design.plots);
}

Json to_json(const Design& design, const SweepStudyResult& r) {
  const SweepStudy& sw = *design.sweep;
  Json j = Json::object();
  j["status"] = r.ok() ? "ok" : r.message;
  j["feedback"] = to_string(sw.feedback);
  j["samples"] = r.samples.size();
  j["completed"] = r.completed;
  j["failed"] = r.failed;
  j["resumed_from_journal"] = r.resumed;
  Json params = Json::array();
  for (const auto& p : sw.parameters) {
    Json e = Json::object();
    e["name"] = to_string(p.name);
    e["distribution"] = to_string(p.kind);
    if (p.kind == SweepParameter::Kind::Normal) {
      e["mean"] = p.a;
      e["std"] = p.b;
    } else {
      e["min"] = p.a;
      e["max"] = p.b;
      if (p.kind == SweepParameter::Kind::Grid) e["points"] = p.points;
    }
    params.push_back(e);
  }
  j["parameters"] = params;
  j["requirement_energy_J"] = sw.requirement_energy_J;
  j["fraction_meeting_requirement"] = r.fraction_meeting;
  // the sampling's own uncertainty: 95% intervals (wilson_interval, quantile_interval)
  j["fraction_meeting_requirement_ci95"] = std::vector<double>{r.fraction_meeting_low, r.fraction_meeting_high};
  Json e = Json::object();
  e["mean"] = r.mean_J;
  e["p05"] = r.p05_J;
  e["p50"] = r.p50_J;
  e["p95"] = r.p95_J;
  if (std::isfinite(r.p95_low_J)) e["p95_ci95"] = std::vector<double>{r.p95_low_J, r.p95_high_J};
  e["worst"] = r.worst_J;
  j["residual_vibration_energy_J"] = e;
  if (!r.error_checks.empty()) {
    // the integration's share ([sweep] error_estimate): samples flown at 10x tighter tolerances
    Json checks = Json::array();
    for (const auto& c : r.error_checks) {
      Json k = Json::object();
      k["role"] = c.role;
      k["sample"] = c.index;
      k["residual_vibration_energy_J"] = c.energy_J;
      if (std::isfinite(c.tight_energy_J)) {
        k["tighter_residual_vibration_energy_J"] = c.tight_energy_J;
        k["change_J"] = std::abs(c.tight_energy_J - c.energy_J);
      } else {
        k["status"] = c.message;
      }
      checks.push_back(k);
    }
    Json ie = Json::object();
    ie["samples"] = checks;
    if (std::isfinite(r.max_relative_error_estimate)) ie["max_relative_change"] = r.max_relative_error_estimate;
    j["integration_error_estimate"] = ie;
  }
  j["threads"] = r.threads;
  j["ranks"] = r.ranks;
  j["wall_time_s"] = r.wall_time_s;
  j["time_per_sample_s"] = r.time_per_sample_s;
  j["cpu_time_per_sample_s"] = r.cpu_time_per_sample_s;
  // the work budget (README, the "(limits)" row): filter and digital law, samples flown here
  j["setup_work_units"] = r.setup_work_units;
  j["sample_work_units"] = r.sample_work_units;
  j["work_share_per_sample_units"] = r.work_share_per_sample;
  return j;
}

}  // namespace freeflex::detail

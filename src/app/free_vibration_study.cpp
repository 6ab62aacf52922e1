// [free_vibration]: frequency sweep over NOA (the paper's Table 1) and mode shapes
// against the exact free-free beam (the paper's Fig. 3).
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "freeflex/analysis/exact_free_free.hpp"
#include "freeflex/analysis/free_vibration.hpp"
#include "freeflex/analysis/paper_reference.hpp"
#include "freeflex/app/run.hpp"
#include "freeflex/io/plot.hpp"
#include "freeflex/model/modal_integrals.hpp"

namespace freeflex {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// True when the closed-form free-free beam applies: one uniform span, no hub, no payload.
bool is_plain_uniform(const Beam& beam) {
  const auto& p = beam.properties();
  for (const auto& s : p.segments)
    if (s.mass_per_length_kg_m != p.segments[0].mass_per_length_kg_m ||
        s.bending_stiffness_Nm2 != p.segments[0].bending_stiffness_Nm2)
      return false;
  for (const auto& pm : p.point_masses)
    if (pm.mass_kg != 0.0) return false;
  return p.hub_mass_kg == 0.0 && p.hub_rotary_inertia_kgm2 == 0.0;
}

}  // namespace

ModeTable mode_table(const Design& design, int noa) {
  const Beam beam(design.beam);
  const FreeVibrationResult fv = free_vibration(modal_integrals(beam, make_basis(beam, noa)));
  ModeTable t;
  t.omega_rad_s = fv.omega;
  t.freq_hz = fv.omega / (2.0 * M_PI);
  t.lambda = fv.omega.unaryExpr([&](double w) {
    return paper_lambda(w, beam.distributed_mass(), beam.length(), beam.mean_bending_stiffness());
  });
  return t;
}

void run_free_vibration(const Design& design, RunOutput& out, Json& summary) {
  const FreeVibrationStudy& study = *design.free_vibration;
  const Beam beam(design.beam);
  const bool exact = is_plain_uniform(beam);
  const std::vector<int> sweep = study.noa_sweep.empty() ? std::vector<int>{design.noa} : study.noa_sweep;
  std::ostream* log = out.log();

  // Frequency table, long format: one row per (NOA, mode).
  std::vector<std::string> header{"noa", "mode", "omega_rad_s", "freq_hz", "lambda"};
  if (study.paper_table) header.push_back("lambda_paper");
  if (exact) header.push_back("lambda_exact");
  int rows = 0;
  for (int n : sweep) rows += std::min(n, study.modes);
  Eigen::MatrixXd table(rows, static_cast<int>(header.size()));
  Json freqs = Json::array();
  int r = 0;
  if (log) *log << "free vibration: " << sweep.size() << " NOA value(s), " << study.modes << " elastic modes\n";
  for (int n : sweep) {
    const ModeTable mt = mode_table(design, n);
    Json entry = Json::object();
    entry["noa"] = n;
    const int shown = std::min(n, study.modes);
    entry["lambda"] = Json::from(mt.lambda.head(shown));
    entry["omega_rad_s"] = Json::from(mt.omega_rad_s.head(shown));
    freqs.push_back(entry);
    if (log) *log << "  NOA " << std::setw(3) << n << "  lambda:";
    for (int k = 1; k <= shown; ++k, ++r) {
      int c = 0;
      table(r, c++) = n;
      table(r, c++) = k;
      table(r, c++) = mt.omega_rad_s(k - 1);
      table(r, c++) = mt.freq_hz(k - 1);
      table(r, c++) = mt.lambda(k - 1);
      if (study.paper_table) table(r, c++) = paper::table1(n, k).value_or(kNaN);
      if (exact) table(r, c++) = free_free_root(k);
      if (log) *log << ' ' << std::fixed << std::setprecision(6) << mt.lambda(k - 1) << std::defaultfloat;
    }
    if (log) *log << '\n';
  }
  out.csv(study.table_name + ".csv", header, table);
  Json fv = Json::object();
  fv["table"] = study.table_name + ".csv";
  fv["frequencies"] = freqs;

  Json shapes = Json::array();
  for (const ModeShapeRequest& req : study.mode_shapes) {
    const AdmissibleBasis basis = make_basis(beam, req.noa);
    const FreeVibrationResult res = free_vibration(modal_integrals(beam, basis));
    if (req.mode > res.omega.size()) {
      out.warn("mode shape '" + req.name + "': NOA " + std::to_string(req.noa) + " has only " +
               std::to_string(res.omega.size()) + " elastic modes");
      continue;
    }
    const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(req.points, beam.x_left(), beam.x_right());
    Eigen::VectorXd w = mode_displacement(basis, res.shapes.col(req.mode - 1), x);
    w /= w.cwiseAbs().maxCoeff();
    std::vector<std::string> cols{"s_m", "x_m", "w_freeflex"};
    Eigen::MatrixXd data(req.points, exact ? 4 : 3);
    data.col(0) = x.array() - beam.x_left();
    data.col(1) = x;
    data.col(2) = w;
    Json entry = Json::object();
    entry["name"] = req.name;
    entry["noa"] = req.noa;
    entry["mode"] = req.mode;
    if (exact) {
      Eigen::VectorXd we(req.points);
      for (int i = 0; i < req.points; ++i) we(i) = free_free_shape(req.mode, data(i, 0) / beam.length());
      we /= we.cwiseAbs().maxCoeff();
      if (we.dot(w) < 0.0) we = -we;  // eigenvectors carry an arbitrary sign
      data.col(3) = we;
      cols.push_back("w_exact");
      entry["max_abs_difference"] = (w - we).cwiseAbs().maxCoeff();
    }
    out.csv(req.name + ".csv", cols, data);
    PlotPanel panel{"", "distance from the left end s [m]", "normalized transverse displacement", {}};
    panel.series.push_back({req.name + ".csv", 1, 3, "freeflex, NOA = " + std::to_string(req.noa), "lines"});
    if (exact) panel.series.push_back({req.name + ".csv", 1, 4, "exact free-free", "points pt 6 ps 0.8"});
    std::ostringstream title;
    title << "Elastic mode " << req.mode << " (NOA = " << req.noa << ")";
    out.plot(PlotSpec{req.name, title.str(), {panel}}, design.plots);
    shapes.push_back(entry);
  }
  fv["mode_shapes"] = shapes;
  summary["free_vibration"] = fv;
}

}  // namespace freeflex

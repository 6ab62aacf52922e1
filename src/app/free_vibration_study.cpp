// [free_vibration]: frequency sweep over NOA (the paper's Table 1) and mode shapes
// against the exact free-free beam (the paper's Fig. 3): the study, its files and its
// summary entry.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "app/study_files.hpp"
#include "freeflex/analysis/exact_free_free.hpp"
#include "freeflex/analysis/free_vibration.hpp"
#include "freeflex/analysis/paper_reference.hpp"
#include "freeflex/io/plot.hpp"
#include "freeflex/model/modal_integrals.hpp"

namespace freeflex {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

bool has_exact_modes(const Design& design) { return design.beam.plain_uniform(); }

ModeTable mode_table(const Design& design, int noa, bool estimate_error) {
  const Beam beam(design.beam);
  const auto basis = make_basis(beam, noa, design.basis);
  const FreeVibrationResult fv = free_vibration(modal_integrals(beam, *basis));
  ModeTable t;
  t.omega_rad_s = fv.omega;
  t.freq_hz = fv.omega / (2.0 * M_PI);
  t.lambda = fv.omega.unaryExpr([&](double w) {
    return paper_lambda(w, beam.distributed_mass(), beam.length(), beam.mean_bending_stiffness());
  });
  if (!estimate_error) return t;
  auto omega_with = [&](int n, const BasisOptions& options) {
    return free_vibration(modal_integrals(beam, *make_basis(beam, n, options))).omega;
  };
  t.error_estimate = Eigen::VectorXd::Constant(noa, kNaN);
  std::ostringstream method;
  const bool fe_basis = design.basis.kind == BasisOptions::Kind::FiniteElement;
  const bool clamped = fe_basis && design.basis.finite_element.modes == FiniteElementOptions::Modes::ClampedAtReference;
  if (fe_basis && !clamped) {
    // eq. 4.4: omega_N - omega_exact ~ (omega_N - omega_2N) 2^r / (2^r - 1), r = 4 or 8
    const auto& fe = static_cast<const FiniteElementBasis&>(*basis);
    const int rate = fe.options().order == 5 ? 8 : 4;
    const double gain = std::pow(2.0, rate);
    BasisOptions other = design.basis;
    if (2 * fe.elements() <= kMaxElements) {
      // against twice the elements: the error of omega_N is (omega_N - omega_2N) 2^r / (2^r - 1)
      other.finite_element.elements = 2 * fe.elements();
      const Eigen::VectorXd omega2 = omega_with(noa, other);
      t.error_estimate = (fv.omega - omega2).cwiseQuotient(fv.omega) * (gain / (gain - 1.0));
    } else {
      // at the largest meshes, against half the elements: (omega_N/2 - omega_N) / (2^r - 1)
      other.finite_element.elements = fe.elements() / 2;
      const Eigen::VectorXd omega_half = omega_with(noa, other);
      t.error_estimate = (omega_half - fv.omega).cwiseQuotient(fv.omega) / (gain - 1.0);
    }
    method << "Richardson, " << fe.elements() << " and " << other.finite_element.elements
           << (fe.options().order == 5 ? " quintic" : " cubic") << " elements at order h^" << rate;
  } else {
    // eq. 4.3: nested Ritz spaces, so omega(noa) - omega(2 noa) is a lower bound of the error
    // (the modes clamped at o nest too: the first noa of a mesh are among its first 2 noa)
    const int most = clamped ? std::min(kMaxNoa, static_cast<const FiniteElementBasis&>(*basis).dofs() - 2) : kMaxNoa;
    const int hi = std::min(2 * noa, most), lo = hi == noa ? noa / 2 : noa;
    const Eigen::VectorXd w_lo = lo == noa ? fv.omega : omega_with(lo, design.basis);
    const Eigen::VectorXd w_hi = hi == noa ? fv.omega : omega_with(hi, design.basis);
    const int common = static_cast<int>(std::min(w_lo.size(), t.error_estimate.size()));
    t.error_estimate.head(common) = (w_lo.head(common) - w_hi.head(common)).cwiseQuotient(fv.omega.head(common));
    method << "change from " << (clamped ? "n " : "NOA ") << lo << " to " << (clamped ? "n " : "NOA ") << hi
           << (clamped ? " modes clamped at o" : "");
  }
  t.error_method = method.str();
  return t;
}

FreeVibrationStudyResult run_free_vibration_study(const Design& design, const StudyLog& study_log) {
  const FreeVibrationStudy& study = *design.free_vibration;
  const Beam beam(design.beam);
  const bool exact = beam.properties().plain_uniform();
  const std::vector<int> sweep = study.noa_sweep.empty() ? std::vector<int>{design.noa} : study.noa_sweep;
  std::ostream* log = study_log.log;
  FreeVibrationStudyResult r;

  // Frequency table, long format: one row per (NOA, mode).
  r.table_header = {"noa", "mode", "omega_rad_s", "freq_hz", "lambda"};
  if (study.paper_table) r.table_header.push_back("lambda_paper");
  if (exact) r.table_header.push_back("lambda_exact");
  // without a closed form, each frequency's estimated error (see mode_table)
  else r.table_header.push_back("error_estimate");
  int rows = 0;
  for (int n : sweep) rows += std::min(n, study.modes);
  r.table.resize(rows, static_cast<int>(r.table_header.size()));
  int row = 0;
  if (log) *log << "free vibration: " << sweep.size() << " NOA value(s), " << study.modes << " elastic modes\n";
  for (int n : sweep) {
    const ModeTable mt = mode_table(design, n, !exact);
    const int shown = std::min(n, study.modes);
    r.frequencies.push_back({n, mt.lambda.head(shown), mt.omega_rad_s.head(shown),
                             exact ? Eigen::VectorXd() : Eigen::VectorXd(mt.error_estimate.head(shown))});
    if (!exact) r.error_method = mt.error_method;
    if (log) *log << "  NOA " << std::setw(3) << n << "  lambda:";
    for (int k = 1; k <= shown; ++k, ++row) {
      int c = 0;
      r.table(row, c++) = n;
      r.table(row, c++) = k;
      r.table(row, c++) = mt.omega_rad_s(k - 1);
      r.table(row, c++) = mt.freq_hz(k - 1);
      r.table(row, c++) = mt.lambda(k - 1);
      if (study.paper_table) r.table(row, c++) = paper::table1(n, k).value_or(kNaN);
      if (exact) r.table(row, c++) = free_free_root(k);
      else r.table(row, c++) = mt.error_estimate(k - 1);
      if (log) *log << ' ' << std::fixed << std::setprecision(6) << mt.lambda(k - 1) << std::defaultfloat;
    }
    if (log) *log << '\n';
  }

  if (!study.spin_rates.empty()) {
    // Frequencies under steady spin, hub held (eq. 14.12), at the model's NOA and basis.
    const ModalIntegrals mi = stiffened_modal_integrals(beam, *make_basis(beam, design.noa, design.basis));
    const int shown = std::min(design.noa, study.modes);
    r.spinning_header = {"spin_rad_s", "mode", "omega2_stiffened", "omega_stiffened_rad_s", "omega2_unstiffened",
                         "omega_unstiffened_rad_s"};
    r.spinning_table.resize(static_cast<int>(study.spin_rates.size()) * shown, 6);
    int row = 0;
    for (double spin : study.spin_rates) {
      const Eigen::VectorXd with = spinning_frequencies_squared(mi, spin, true);
      const Eigen::VectorXd without = spinning_frequencies_squared(mi, spin, false);
      auto root = [](double w2) { return w2 >= 0.0 ? std::sqrt(w2) : kNaN; };
      for (int k = 0; k < shown; ++k, ++row)
        r.spinning_table.row(row) << spin, k + 1, with(k), root(with(k)), without(k), root(without(k));
      if (without(0) < 0.0) {
        const std::string why = "at a spin of " + std::to_string(spin) +
                                " rad/s the model without geometric stiffening has buckled (first omega^2 = " +
                                std::to_string(without(0)) + " < 0); with stiffening omega = " +
                                std::to_string(root(with(0))) + " rad/s";
        r.warnings.push_back(why);
        if (study_log.warn) study_log.warn(why);
      }
    }
  }

  for (const ModeShapeRequest& req : study.mode_shapes) {
    const auto basis = make_basis(beam, req.noa, design.basis);
    const FreeVibrationResult res = free_vibration(modal_integrals(beam, *basis));
    if (req.mode > res.omega.size()) {
      const std::string why = "mode shape '" + req.name + "': NOA " + std::to_string(req.noa) + " has only " +
                              std::to_string(res.omega.size()) + " elastic modes";
      r.warnings.push_back(why);
      if (study_log.warn) study_log.warn(why);
      continue;
    }
    const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(req.points, beam.x_left(), beam.x_right());
    Eigen::VectorXd w = mode_displacement(*basis, res.shapes.col(req.mode - 1), x);
    w /= w.cwiseAbs().maxCoeff();
    FreeVibrationStudyResult::ModeShape shape;
    shape.name = req.name;
    shape.noa = req.noa;
    shape.mode = req.mode;
    shape.header = {"s_m", "x_m", "w_freeflex"};
    Eigen::MatrixXd& data = shape.data;
    data.resize(req.points, exact ? 4 : 3);
    data.col(0) = x.array() - beam.x_left();
    data.col(1) = x;
    data.col(2) = w;
    if (exact) {
      Eigen::VectorXd we(req.points);
      for (int i = 0; i < req.points; ++i) we(i) = free_free_shape(req.mode, data(i, 0) / beam.length());
      we /= we.cwiseAbs().maxCoeff();
      if (we.dot(w) < 0.0) we = -we;  // eigenvectors carry an arbitrary sign
      data.col(3) = we;
      shape.header.push_back("w_exact");
      shape.max_abs_difference = (w - we).cwiseAbs().maxCoeff();
    }
    r.mode_shapes.push_back(std::move(shape));
  }
  return r;
}

namespace detail {

void write_free_vibration(const Design& design, const FreeVibrationStudyResult& r, RunOutput& out) {
  const FreeVibrationStudy& study = *design.free_vibration;
  out.csv(study.table_name + ".csv", r.table_header, r.table);
  if (r.spinning_table.size()) out.csv(study.spinning_table_name + ".csv", r.spinning_header, r.spinning_table);
  for (const auto& shape : r.mode_shapes) {
    out.csv(shape.name + ".csv", shape.header, shape.data);
    PlotPanel panel{"", "distance from the left end s [m]", "normalized transverse displacement", {}};
    panel.series.push_back({shape.name + ".csv", 1, 3, "freeflex, NOA = " + std::to_string(shape.noa), "lines"});
    if (shape.max_abs_difference)
      panel.series.push_back({shape.name + ".csv", 1, 4, "exact free-free", "points pt 6 ps 0.8"});
    std::ostringstream title;
    title << "Elastic mode " << shape.mode << " (NOA = " << shape.noa << ")";
    out.plot(PlotSpec{shape.name, title.str(), {panel}}, design.plots);
  }
}

Json to_json(const Design& design, const FreeVibrationStudyResult& r) {
  Json fv = Json::object();
  fv["table"] = design.free_vibration->table_name + ".csv";
  Json freqs = Json::array();
  for (const auto& f : r.frequencies) {
    Json entry = Json::object();
    entry["noa"] = f.noa;
    entry["lambda"] = json_array(f.lambda);
    entry["omega_rad_s"] = json_array(f.omega_rad_s);
    if (f.error_estimate.size() > 0) entry["error_estimate"] = json_array(f.error_estimate);
    freqs.push_back(entry);
  }
  fv["frequencies"] = freqs;
  if (r.spinning_table.size()) fv["spinning_table"] = design.free_vibration->spinning_table_name + ".csv";
  if (!r.error_method.empty()) fv["error_method"] = r.error_method;
  Json shapes = Json::array();
  for (const auto& shape : r.mode_shapes) {
    Json entry = Json::object();
    entry["name"] = shape.name;
    entry["noa"] = shape.noa;
    entry["mode"] = shape.mode;
    if (shape.max_abs_difference) entry["max_abs_difference"] = *shape.max_abs_difference;
    shapes.push_back(entry);
  }
  fv["mode_shapes"] = shapes;
  return fv;
}

}  // namespace detail
}  // namespace freeflex

// Every study flies the body the design describes: on the finite-element basis (the
// stepped beam with hub and tip mass, designs/suppress_stepped_hub_tip.toml) the [export]'s
// LTV model and the [lqg]/[sweep] flights' first-order model are the suppression study's,
// not one built on the paper's basis (the defect found in the hardening issue: both
// rebuilt the body from the beam and NOA alone).
#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>

#include "app/sweep_files.hpp"
#include "freeflex/freeflex.hpp"
#include "support/cli.hpp"

using namespace freeflex;

namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// The suppression study's first-order model, as suppress_vibration builds it.
std::unique_ptr<FirstOrderModel> law_model(const Design& d, const FlexibleBody& body, const SuppressionResult& chain) {
  return std::make_unique<FirstOrderModel>(
      body, *chain.nominal, nominal_element_commands(d.excitation(), d.controller->actuators, chain.u0),
      d.controller->actuators);
}

}  // namespace

TEST_CASE("[export] and the [lqg]/[sweep] flights use the design's basis", "[app]") {
  const std::string text = read_text(std::string(FREEFLEX_SOURCE_DIR) + "/designs/suppress_stepped_hub_tip.toml") +
                           "\n[export]\nformats = [\"csv\"]\ncontents = [\"model\"]\nmodel_step_s = 0.5\n";
  const Design d = parse_design(text, "stepped+export");
  REQUIRE(d.basis.kind == BasisOptions::Kind::FiniteElement);
  RunOptions ro;
  ro.out_dir = freeflex_test::temp_path("basis_export");
  ro.plot.gnuplot = "";  // no figures
  const RunResult r = run_design(d, ro);
  REQUIRE(r.ok());
  REQUIRE(r.suppression);
  const SuppressionResult& chain = r.suppression->chain;
  REQUIRE(chain.nominal);
  const FlexibleBody body = d.body();
  const auto model = law_model(d, body, chain);
  const int n = model->state_size(), m = model->input_size();

  // The exported A(t) at every model grid time against the law's model there.
  std::ifstream csv(ro.out_dir + "/controller_model.csv");
  REQUIRE(csv.good());
  std::string line;
  std::getline(csv, line);  // header
  int rows = 0;
  double worst = 0.0, scale = 0.0;
  while (std::getline(csv, line)) {
    std::vector<double> v;
    std::stringstream ls(line);
    for (std::string cell; std::getline(ls, cell, ',');) v.push_back(std::stod(cell));
    REQUIRE(static_cast<int>(v.size()) == 3 + n * n + n * m + n);
    const StateSpace ss = model->state_space(Instant{v[1], v[2]});
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) {
        worst = std::max(worst, std::abs(v[3 + a * n + b] - ss.A(a, b)));
        scale = std::max(scale, std::abs(ss.A(a, b)));
      }
    ++rows;
  }
  INFO(rows << " rows, largest |A_export - A| " << worst << " of " << scale);
  CHECK(rows > 4);
  CHECK(worst <= 1e-12 * scale);  // the same model written with 17 significant digits: round-off only

  // The [lqg]/[sweep] flights' model (detail::Flight) against the law's model.
  const detail::Flight f(d, *r.suppression, r.maneuver ? &*r.maneuver : nullptr);
  double diff = 0.0, size = 0.0;
  for (double t : {0.0, 0.7, 1.9, 3.1}) {
    const StateSpace a = f.model->state_space(Instant::at(t)), b = model->state_space(Instant::at(t));
    diff = std::max({diff, (a.A - b.A).cwiseAbs().maxCoeff(), (a.B - b.B).cwiseAbs().maxCoeff()});
    size = std::max(size, b.A.cwiseAbs().maxCoeff());
  }
  INFO("largest |A_flight - A| " << diff << " of " << size);
  CHECK(diff == 0.0);  // built from the same body, nominal and commands: identical
  // and on the paper's basis the model differs (the test sees the basis)
  const FlexibleBody paper(Beam(d.beam), d.noa, d.force_elements(), d.damping_ratios);
  const auto other = law_model(d, paper, chain);
  CHECK((other->state_space(Instant::at(0.7)).A - model->state_space(Instant::at(0.7)).A).cwiseAbs().maxCoeff() >
        1e-3 * size);
}

TEST_CASE("lqg.png draws each case's commands against the limits", "[app]") {
  const Design d = load_design(std::string(FREEFLEX_SOURCE_DIR) + "/designs/lqg_slew.toml");
  RunOptions ro;
  ro.out_dir = freeflex_test::temp_path("lqg_commands");
  ro.plot.gnuplot = "";  // the scripts, no PNG
  const RunResult r = run_design(d, ro);
  REQUIRE(r.ok());
  REQUIRE(r.lqg);
  const std::string gp = read_text(ro.out_dir + "/" + d.lqg->figure + ".gp");
  CHECK_THAT(gp, Catch::Matchers::Contains("commands u0 + u1 as computed") &&
                     Catch::Matchers::Contains("command limits"));
  std::ifstream csv(ro.out_dir + "/" + d.lqg->table + "_history.csv");
  std::string header, first;
  std::getline(csv, header);
  std::getline(csv, first);
  // one column per case and actuator, after the tip and energy columns
  const auto& c = r.lqg->cases.back();
  const std::string column = "u_" + c.name + "_" + d.controller->actuator_names.back();
  CHECK_THAT(header, Catch::Matchers::EndsWith(column));
  const double last = std::stod(first.substr(first.rfind(',') + 1));
  CHECK(last == Approx(c.run.commands(0, c.run.commands.cols() - 1)).margin(1e-15));  // the value written (17 digits)
}

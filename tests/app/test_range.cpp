// Runs that know their range (issue 14, acceptance 6): the warning of a model without
// stiffening spun near its first frequency, none for a motion far from it, and an
// unbounded response reported out_of_range with its reason.
#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>
#include <string>

#include "freeflex/app/studies.hpp"
#include "freeflex/io/design.hpp"

using namespace freeflex;

namespace {
std::string shipped(const std::string& stem) {
  std::ifstream in(std::string(FREEFLEX_SOURCE_DIR) + "/designs/" + stem + ".toml");
  REQUIRE(in);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}
bool mentions(const std::vector<std::string>& warnings, const std::string& what) {
  for (const auto& w : warnings)
    if (w.find(what) != std::string::npos) return true;
  return false;
}
/// `text` with the first occurrence of `from` replaced by `to` (which must be there).
std::string edited(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}
}  // namespace

TEST_CASE("the KRB spin-up: stiffened ok, without stiffening a warning and out_of_range", "[app]") {
  const std::string text = shipped("spinup_krb");
  {
    const Design d = parse_design(edited(text, "compare_stiffening = true", "compare_stiffening = false"), "krb.toml");
    const SimulationStudyResult r = run_simulation_study(d);
    INFO(r.message);
    CHECK(r.ok());
    CHECK_FALSE(mentions(r.warnings, "without geometric stiffening"));
    REQUIRE(r.nonlinear);
    CHECK(r.nonlinear->range.spin_ratio == Approx(4.0 / 3.7977305).epsilon(1e-6));
    CHECK(r.nonlinear->range.deflection_ratio == Approx(0.0400).margin(1e-4));  // 0.4003 m of 10 m
    // the energy balance of the prescribed motion: work of the hub against the energy (measured 4e-11)
    REQUIRE(r.nonlinear->range.energy_balance_error_rel);
    CHECK(*r.nonlinear->range.energy_balance_error_rel < 1e-8);
    // summary.json's variables are those integrated: q in physical coordinates under a
    // prescribed motion, whatever first_order_variables says (its default is modal)
    CHECK(r.full_variables == SimulationOptions::Variables::Physical);
    CHECK(r.first_order_variables == SimulationOptions::Variables::Physical);
  }
  {
    std::string off = edited(text, "geometric_stiffening = true", "geometric_stiffening = false");
    off = edited(off, "compare_stiffening = true", "compare_stiffening = false");
    const Design d = parse_design(off, "krb_off.toml");
    const SimulationStudyResult r = run_simulation_study(d);
    CHECK(r.status == StudyStatus::OutOfRange);
    CHECK_THAT(r.message, Catch::Matchers::Contains("grows without bound") && Catch::Matchers::Contains("t = 13.38"));
    CHECK(mentions(r.warnings, "in a model without geometric stiffening"));
    REQUIRE(r.nonlinear);
    CHECK(r.nonlinear->table.rows() == 1339);  // 0 .. 13.38 s: written up to where it left
    CHECK(std::string(to_string(r.status)) == "out_of_range");
  }
}

TEST_CASE("a shipped motion far from its range draws no range warning", "[app]") {
  // the paper's force pulse translates the beam (no spin), tiny deflections
  const Design d = parse_design(shipped("paper_force_pulse"), "paper_force_pulse.toml");
  const SimulationStudyResult r = run_simulation_study(d);
  INFO(r.message);
  CHECK(r.ok());
  CHECK(r.warnings.empty());
  REQUIRE(r.nonlinear);
  CHECK(r.nonlinear->range.spin_ratio < 1e-6);  // rotation held at zero to ~atol
  CHECK(r.nonlinear->range.deflection_ratio < 0.1);
  // its full model runs in modal variables: no energy balance (their steps alias the power)
  CHECK_FALSE(r.nonlinear->range.energy_balance_error_rel);
}

TEST_CASE("stiffened: the range shrinks as noa grows, and the message says why", "[app]") {
  // The paper's beam under a 0.5 N tip force for 0.2 s (docs/theory.md section 14): the
  // frame keeps 1.4e-3 of the rotary inertia at noa 6 and 1.2e-4 at noa 14, where the
  // second-order mass matrix fails at 0.124 s with a 1.4 % deflection.
  const std::string text = R"(title = "stiffened range"
[beam]
length_m = 1.0
mass_kg = 1.0
bending_stiffness_Nm2 = 1.0
[model]
noa = NOA
geometric_stiffening = true
[[load]]
name = "tip"
type = "force"
position_m = 1.0
direction = [0.0, 1.0]
[load.profile]
type = "steps"
times_s = [0.0, 0.2]
values = [0.5]
[simulation]
duration_s = 0.2
output_step_s = 0.002
rtol = 1e-8
atol = 1e-12
error_estimate = false
)";
  {
    const SimulationStudyResult r = run_simulation_study(parse_design(edited(text, "NOA", "6"), "noa6.toml"));
    INFO(r.message);
    CHECK(r.ok());
  }
  const SimulationStudyResult r = run_simulation_study(parse_design(edited(text, "NOA", "14"), "noa14.toml"));
  CHECK(r.status == StudyStatus::OutOfRange);
  CHECK_THAT(r.message, Catch::Matchers::Contains("t = 0.1239") &&
                            Catch::Matchers::Contains("the frame keeps by itself 0.00012 of the rotary inertia") &&
                            Catch::Matchers::Contains("fewer shape functions widen the range"));
}

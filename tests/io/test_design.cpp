// Design files: whole-file validation, messages naming key and line, unknown keys.
#include <catch2/catch.hpp>

#include "freeflex/io/design.hpp"

using namespace freeflex;
using Catch::Contains;

namespace {
const char* kGood = R"(title = "ok"
[beam]
length_m = 2.0
mass_kg = 3.0
bending_stiffness_Nm2 = 5.0
[model]
noa = 8
)";

std::string problems_of(const std::string& text) {
  try {
    parse_design(text, "t.toml");
  } catch (const DesignError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("a good design loads with units and defaults", "[io]") {
  const Design d = parse_design(kGood, "t.toml");
  REQUIRE(d.beam.segments.size() == 1);
  CHECK(d.beam.segments[0].length_m == 2.0);
  CHECK(d.beam.segments[0].mass_per_length_kg_m == 1.5);
  CHECK(d.noa == 8);
  CHECK(d.plots);
  CHECK(!d.free_vibration);
}

TEST_CASE("the paper's design file loads", "[io]") {
  const Design d = load_design(std::string(FREEFLEX_SOURCE_DIR) + "/designs/paper_table1.toml");
  REQUIRE(d.free_vibration);
  CHECK(d.free_vibration->noa_sweep == std::vector<int>{2, 4, 6, 8, 10});
  REQUIRE(d.free_vibration->mode_shapes.size() == 1);
  CHECK(d.free_vibration->mode_shapes[0].mode == 4);
}

TEST_CASE("bad values name key, line, value and allowed range", "[io]") {
  CHECK_THAT(problems_of("[beam]\nlength_m = -1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n"),
             Contains("design 't.toml' line 2: beam.length_m = -1, must be > 0"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 0\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n"),
             Contains("line 2: beam.length_m = 0, must be > 0"));
  CHECK_THAT(problems_of("[beam]\nlength_m = \"one\"\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n"),
             Contains("line 2: beam.length_m = \"one\", must be a number"));
  CHECK_THAT(problems_of("[beam]\nlength_m = nan\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n"),
             Contains("line 2: beam.length_m = nan, must be a finite number"));
  CHECK_THAT(problems_of(std::string(kGood) + "noa_typo = 3\n"),
             Contains("line 8: unknown key 'model.noa_typo' (allowed here: noa)"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n[model]\nnoa = 0\n"),
             Contains("line 6: model.noa = 0, must be a whole number in [1, 100]"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n[model]\nnoa = 101\n"),
             Contains("model.noa = 101, must be a whole number in [1, 100]"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n[beam.hub]\nmass_kg = -2\n"),
             Contains("line 6: beam.hub.mass_kg = -2, must be >= 0"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n[[beam.point_mass]]\n"
                         "position_m = 1.5\nmass_kg = 0.1\n"),
             Contains("line 6: beam.point_mass[1].position_m = 1.5, must be in [0, 1]"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\nreference_m = 1.0\n"),
             Contains("line 5: beam.reference_m = 1.0, must be in (0, 1)"));
}

TEST_CASE("every problem is reported at once", "[io]") {
  try {
    parse_design("colour = 3\n[beam]\nlength_m = -1\nmass_kg = \"x\"\n[model]\nnoa = 1.5\n", "t.toml");
    FAIL("expected a DesignError");
  } catch (const DesignError& e) {
    const std::string all = e.what();
    CHECK(e.problems().size() == 5);
    CHECK_THAT(all, Contains("line 1: unknown key 'colour'"));
    CHECK_THAT(all, Contains("line 3: beam.length_m = -1"));
    CHECK_THAT(all, Contains("line 4: beam.mass_kg = \"x\", must be a number"));
    CHECK_THAT(all, Contains("line 2: beam.bending_stiffness_Nm2 is required"));
    CHECK_THAT(all, Contains("line 6: model.noa = 1.5, must be a whole number"));
  }
}

TEST_CASE("syntax errors and missing files", "[io]") {
  CHECK_THAT(problems_of("[beam\nlength_m = 1\n"), Contains("design 't.toml' line 1: not valid TOML"));
  CHECK_THROWS_WITH(load_design("/nonexistent/x.toml"),
                    Contains("design '/nonexistent/x.toml': cannot open the file"));
  CHECK_THAT(problems_of("title = \"no beam\"\n"), Contains("section [beam] is required"));
}

namespace {
const std::string kPaperBeam = "[beam]\nlength_m = 1.0\nmass_kg = 1.0\nbending_stiffness_Nm2 = 1.0\n";  // lines 1-4
const std::string kLoad =  // lines 5-13
    "[[load]]\nname = \"F\"\ntype = \"force\"\nposition_m = 0.5\ndirection = [0.0, 1.0]\n"
    "[load.profile]\ntype = \"steps\"\ntimes_s = [0.0, 0.5, 1.0]\nvalues = [1.0, -1.0]\n";
}  // namespace

TEST_CASE("loads, actuators and simulation keys load", "[io]") {
  const Design d = parse_design(kPaperBeam + kLoad +
                                    "[[actuator]]\nname = \"tip\"\ntype = \"thruster\"\nposition_m = 1.0\n"
                                    "direction = [0, 1]\nfollow_slope = true\nlimit = 2.0\n"
                                    "[damping]\nratios = [0.01, 0.02]\n[simulation]\nduration_s = 2.0\nrtol = 1e-9\n",
                                "t.toml");
  REQUIRE(d.loads.size() == 1);
  CHECK(d.loads[0].profile.value(0.7) == -1.0);
  REQUIRE(d.actuators.size() == 1);
  CHECK(d.actuators[0].element.follow_slope);
  CHECK(d.actuators[0].limit == 2.0);
  CHECK(d.damping_ratios == std::vector<double>{0.01, 0.02});
  REQUIRE(d.simulation);
  CHECK(d.simulation->options.integrator.rtol == 1e-9);
  CHECK(d.simulation->options.output_step_s == Approx(2.0 / 600));
  // defaults: modal variables for the first-order model, physical for the full one
  CHECK(d.simulation->options.first_order_variables == SimulationOptions::Variables::Modal);
  CHECK(d.simulation->options.full_variables == SimulationOptions::Variables::Physical);
  CHECK(d.force_elements().size() == 2);
  const Design swapped = parse_design(kPaperBeam + kLoad +
                                          "[simulation]\nduration_s = 2.0\nfull_model_variables = \"modal\"\n"
                                          "first_order_variables = \"physical\"\n",
                                      "t.toml");
  REQUIRE(swapped.simulation);
  CHECK(swapped.simulation->options.full_variables == SimulationOptions::Variables::Modal);
  CHECK(swapped.simulation->options.first_order_variables == SimulationOptions::Variables::Physical);
}

TEST_CASE("bad loads and tolerances name key and line", "[io]") {
  std::string off_beam = kLoad;
  off_beam.replace(off_beam.find("position_m = 0.5"), 16, "position_m = 1.5");
  CHECK_THAT(problems_of(kPaperBeam + off_beam), Contains("line 8: load[1].position_m = 1.5, must be in [0, 1]"));
  std::string decreasing = kLoad;
  decreasing.replace(decreasing.find("[0.0, 0.5, 1.0]"), 15, "[0.0, 0.7, 0.5]");
  CHECK_THAT(problems_of(kPaperBeam + decreasing),
             Contains("line 12: load[1].profile.times_s must be strictly increasing: entry 3 (0.5) does not exceed "
                      "entry 2 (0.7)"));
  CHECK_THAT(problems_of(kPaperBeam + kLoad + "[simulation]\nduration_s = 1.0\nrtol = -1e-8\n"),
             Contains("line 16: simulation.rtol = -1e-08, must be in (0, 1)"));
  CHECK_THAT(problems_of(kPaperBeam + kLoad + "[simulation]\nduration_s = 1.0\natol = -1e-10\n"),
             Contains("line 16: simulation.atol = -1e-10, must be > 0"));
  CHECK_THAT(problems_of(kPaperBeam + kLoad + "[simulation]\nduration_s = 1.0\nfull_model_variables = \"eigen\"\n"),
             Contains("line 16: simulation.full_model_variables"));
  CHECK_THAT(problems_of(kPaperBeam + kLoad + "[simulation]\nduration_s = 0\n"),
             Contains("line 15: simulation.duration_s = 0, must be > 0"));
  std::string wrong_count = kLoad;
  wrong_count.replace(wrong_count.find("values = [1.0, -1.0]"), 20, "values = [1.0]");
  CHECK_THAT(problems_of(kPaperBeam + wrong_count),
             Contains("load[1].profile.values has 1 entries, must have 2 (one per interval between times_s)"));
  CHECK_THAT(problems_of(kPaperBeam + kLoad + kLoad), Contains("load[2].name = \"F\" is used twice"));
  CHECK_THAT(problems_of(kPaperBeam + "[simulation]\nduration_s = 1.0\n"), Contains("needs at least one [[load]]"));
}

TEST_CASE("maneuver keys load; unknown actuator names and bad weights are reported", "[io]") {
  const std::string act = "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 0.5\nlimit = 2.0\n";  // 5-9
  const Design d = parse_design(kPaperBeam + act +
                                    "[maneuver]\nactuators = [\"hub\"]\nobjective = \"time\"\nduration_max_s = 4.0\n"
                                    "transcription = \"trapezoidal\"\nintervals = 40\n[maneuver.final]\ntheta_deg = 90\n"
                                    "[maneuver.ipopt]\nmu_strategy = \"adaptive\"\nacceptable_iter = 5\n",
                                "t.toml");
  REQUIRE(d.maneuver);
  const ManeuverProblem& p = d.maneuver->problem;
  CHECK(p.actuators == std::vector<int>{0});
  CHECK(p.u_max(0) == 2.0);
  CHECK(p.u_min(0) == -2.0);
  CHECK(p.free_time);
  CHECK(p.w_time == 1.0);
  CHECK(p.t_max_s == 4.0);
  CHECK(p.x_final(2) == Approx(M_PI / 2));
  CHECK(d.maneuver->options.transcription == Transcription::Trapezoidal);
  CHECK(d.maneuver->options.ipopt_options.size() == 2);
  CHECK_THAT(problems_of(kPaperBeam + act + "[maneuver]\nactuators = [\"tip\"]\nduration_s = 1.0\n"),
             Contains("line 11: maneuver.actuators: \"tip\" is not an [[actuator]] (known: 'hub')"));
  CHECK_THAT(problems_of(kPaperBeam + act + "[maneuver]\nactuators = [\"hub\"]\nobjective = \"time\"\nfree_duration = false\n"),
             Contains("objective \"time\" needs a free duration"));
  CHECK_THAT(problems_of(kPaperBeam + act + "[maneuver]\nactuators = [\"hub\"]\nduration_s = -3\n"),
             Contains("line 12: maneuver.duration_s = -3, must be > 0"));
}

TEST_CASE("controller keys load; bad weights, horizons and names are reported", "[io]") {
  const std::string acts = kLoad +  // lines 5-13
                           "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 0.5\nlimit = 1.0\n";  // 14-18
  const Design d = parse_design(kPaperBeam + acts +
                                    "[controller]\nactuators = [\"hub\"]\nhorizon_s = 3.0\nweight_elastic = 5.0\n"
                                    "input_weights = [2.0]\n",
                                "t.toml");
  REQUIRE(d.controller);
  CHECK(d.controller->actuators == std::vector<int>{1});  // after the one load
  CHECK(d.controller->limits(0) == 1.0);
  CHECK(d.controller->input_weights(0) == 2.0);
  CHECK(d.controller->weight_elastic == 5.0);
  const std::string head = kPaperBeam + acts + "[controller]\nactuators = [\"hub\"]\n";  // [controller] line 19
  CHECK_THAT(problems_of(head + "horizon_s = 3.0\nweight_elastic = -1.0\n"),
             Contains("line 22: controller.weight_elastic = -1.000000, must be >= 0 (the state weight Q must be "
                      "positive semidefinite)"));
  CHECK_THAT(problems_of(head + "horizon_s = 3.0\ninput_weights = [0.0]\n"),
             Contains("line 22: controller.input_weights: every entry must be > 0 (the input weight R must be "
                      "positive definite)"));
  CHECK_THAT(problems_of(head + "horizon_s = 0.5\n"),
             Contains("line 21: controller.horizon_s = 0.500000, shorter than the maneuver (its loads act until "
                      "1.000000 s)"));
  CHECK_THAT(problems_of(kPaperBeam + acts + "[controller]\nactuators = [\"rudder\"]\nhorizon_s = 3.0\n"),
             Contains("line 20: controller.actuators: \"rudder\" is not an [[actuator]] (known: 'hub')"));
}

// Design files: whole-file validation, messages naming key and line, unknown keys; the
// keys of every section.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "freeflex/io/design.hpp"
#include "support/designs.hpp"

using namespace freeflex;
using namespace freeflex_test;
using Catch::Contains;
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
             Contains("line 8: unknown key 'model.noa_typo' (allowed here: basis, element_order, elements, fe_modes, "
                      "geometric_stiffening, noa)"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n[model]\nnoa = 0\n"),
             Contains("line 6: model.noa = 0, must be a whole number in [1, 100]"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n[model]\nnoa = 101\n"),
             Contains("model.noa = 101, must be a whole number in [1, 100]"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n[beam.hub]\nmass_kg = -2\n"),
             Contains("line 6: beam.hub.mass_kg = -2, must be >= 0"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n[[beam.point_mass]]\n"
                         "position_m = 1.5\nmass_kg = 0.1\n"),
             Contains("line 6: beam.point_mass[1].position_m = 1.5, must be in [0, 1]"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\nreference_m = 1.5\n"),
             Contains("line 5: beam.reference_m = 1.5, must be in [0, 1]"));
  // o at either end: a cantilever clamped at o
  CHECK(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\nreference_m = 1.0\n").empty());
  CHECK(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\nreference_m = 0.0\n").empty());
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
  CHECK(d.simulation->options.output_step_s == Approx(2.0 / 600).epsilon(1e-15));  // duration / count: a rounding or two
  // defaults: modal variables for the first-order model, physical for the full one
  CHECK(d.simulation->options.first_order_variables == SimulationOptions::Variables::Modal);
  CHECK(d.simulation->options.full_variables == SimulationOptions::Variables::Physical);
  CHECK(d.simulation->error_estimate);  // on by default
  CHECK(d.force_elements().size() == 2);
  const Design swapped = parse_design(kPaperBeam + kLoad +
                                          "[simulation]\nduration_s = 2.0\nfull_model_variables = \"modal\"\n"
                                          "first_order_variables = \"physical\"\nerror_estimate = false\n",
                                      "t.toml");
  REQUIRE(swapped.simulation);
  CHECK(swapped.simulation->options.full_variables == SimulationOptions::Variables::Modal);
  CHECK(swapped.simulation->options.first_order_variables == SimulationOptions::Variables::Physical);
  CHECK_FALSE(swapped.simulation->error_estimate);
  CHECK_THAT(problems_of(kPaperBeam + kLoad + "[simulation]\nduration_s = 2.0\nerror_estimate = 1\n"),
             Contains("error_estimate"));
  // rest-mode coordinates: the full model's, with or without geometric stiffening
  const Design rest =
      parse_design(kPaperBeam + kLoad + "[simulation]\nduration_s = 2.0\nfull_model_variables = \"rest_modes\"\n", "t.toml");
  CHECK(rest.simulation->options.full_variables == SimulationOptions::Variables::RestModes);
  CHECK_THAT(problems_of(kPaperBeam + kLoad + "[simulation]\nduration_s = 2.0\nfirst_order_variables = \"rest_modes\"\n"),
             Contains("line 16") && Contains("first_order_variables") && Contains("expected physical or modal"));
  // the first-order solver: the integrator unless asked; "taylor" not with a prescribed motion
  CHECK(d.simulation->options.first_order_solver == SimulationOptions::FirstOrderSolver::Integrator);
  const Design taylor = parse_design(kPaperBeam + kLoad + "[simulation]\nduration_s = 2.0\nfirst_order_solver = \"taylor\"\n",
                                     "t.toml");
  CHECK(taylor.simulation->options.first_order_solver == SimulationOptions::FirstOrderSolver::Taylor);
  const std::string bad = problems_of(kPaperBeam + kLoad + "[simulation]\nduration_s = 2.0\nfirst_order_solver = \"euler\"\n");
  CHECK_THAT(bad, Contains("first_order_solver") && Contains("integrator") && Contains("taylor") && Contains("line"));
  const std::string prescribed =
      problems_of(kPaperBeam + "[motion.theta]\ntype = \"spin_up\"\nfinal_rate_deg_s = 180.0\nramp_time_s = 2.0\n"
                               "[simulation]\nduration_s = 1.0\nfirst_order_solver = \"taylor\"\n");
  CHECK_THAT(prescribed, Contains("first_order_solver") && Contains("prescribed [motion]"));
  // nor other full-model variables than physical: the prescribed motion integrates q alone
  const std::string prescribed_rest =
      problems_of(kPaperBeam + "[motion.theta]\ntype = \"spin_up\"\nfinal_rate_deg_s = 180.0\nramp_time_s = 2.0\n"
                               "[simulation]\nduration_s = 1.0\nfull_model_variables = \"rest_modes\"\n");
  CHECK_THAT(prescribed_rest, Contains("full_model_variables") && Contains("prescribed [motion]") && Contains("line 11"));
  CHECK_THAT(problems_of(kPaperBeam + kLoad + "[simulation]\nduration_s = 2.0\nrtol = 1e-11\nfirst_order_solver = \"taylor\"\n"),
             Contains("rtol = 1e-11") && Contains("expected >= 1e-10"));
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
             Contains("line 16: simulation.atol = -1e-10, must be in (0, 1)"));
  // an absolute tolerance of 1 or more turns the error control off: a wrong result, not an error
  CHECK_THAT(problems_of(kPaperBeam + kLoad + "[simulation]\nduration_s = 1.0\natol = 99999999999\n"),
             Contains("line 16: simulation.atol = 99999999999, must be in (0, 1)"));
  CHECK_THAT(problems_of(kPaperBeam + kLoad + "[simulation]\nduration_s = 1.0\nfull_model_variables = \"eigen\"\n"),
             Contains("line 16: simulation.full_model_variables"));
  // the integration methods, freeflex's own DOP853 among them, are listed
  CHECK_THAT(problems_of(kPaperBeam + kLoad + "[simulation]\nduration_s = 1.0\nmethod = \"rk45\"\n"),
             Contains("line 16: simulation.method") && Contains("dop853"));
  // the explicit pairs' steps take 12 to 16 right-hand sides: ten times an Adams step's
  // work units against the study's budget
  const Design rk = parse_design(kPaperBeam + kLoad + "[simulation]\nduration_s = 1.0\nmethod = \"verner98\"\n", "t.toml");
  REQUIRE(rk.simulation);
  CHECK(rk.simulation->options.integrator.method == IntegratorOptions::Method::Verner98);
  for (long dim : {18L, 46L})
    for (auto m : {IntegratorOptions::Method::Dop853, IntegratorOptions::Method::Verner98})
      CHECK(step_work(dim, m) == 10 * step_work(dim, IntegratorOptions::Method::Adams));
  CHECK_THAT(problems_of(kPaperBeam + kLoad + "[simulation]\nduration_s = 0\n"),
             Contains("line 15: simulation.duration_s = 0, must be > 0"));
  std::string wrong_count = kLoad;
  wrong_count.replace(wrong_count.find("values = [1.0, -1.0]"), 20, "values = [1.0]");
  CHECK_THAT(problems_of(kPaperBeam + wrong_count),
             Contains("load[1].profile.values has 1 entries, must have 2 (one per interval between times_s)"));
  CHECK_THAT(problems_of(kPaperBeam + kLoad + kLoad), Contains("load[2].name = \"F\" is used twice"));
  CHECK_THAT(problems_of(kPaperBeam + "[simulation]\nduration_s = 1.0\n"), Contains("needs at least one [[load]]"));
}

// (no ";" in test names: catch_discover_tests splits on it, and ctest then runs neither half)
TEST_CASE("maneuver keys load, unknown actuator names and bad weights are reported", "[io]") {
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
  CHECK(p.x_final(2) == Approx(M_PI / 2).epsilon(1e-15));  // degrees to radians: a rounding or two
  CHECK(d.maneuver->options.transcription == Transcription::Trapezoidal);
  CHECK(d.maneuver->options.ipopt_options.size() == 2);
  CHECK_THAT(problems_of(kPaperBeam + act + "[maneuver]\nactuators = [\"tip\"]\nduration_s = 1.0\n"),
             Contains("line 11: maneuver.actuators: \"tip\" is not an [[actuator]] (known: 'hub')"));
  CHECK_THAT(problems_of(kPaperBeam + act + "[maneuver]\nactuators = [\"hub\"]\nobjective = \"time\"\nfree_duration = false\n"),
             Contains("objective \"time\" needs a free duration"));
  CHECK_THAT(problems_of(kPaperBeam + act + "[maneuver]\nactuators = [\"hub\"]\nduration_s = -3\n"),
             Contains("line 12: maneuver.duration_s = -3, must be > 0"));
}

TEST_CASE("what the maneuver library checks itself is reported at the design's keys", "[io]") {
  const std::string act = "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 0.5\nlimit = 2.0\n";  // 5-9
  const std::string head = kPaperBeam + act + "[maneuver]\nactuators = [\"hub\"]\n";  // [maneuver] line 10
  // bounds of a free duration in the wrong order (lines 12, 13)
  CHECK_THAT(problems_of(head + "objective = \"time\"\nduration_min_s = 5.0\nduration_max_s = 2.0\n"),
             Contains("line 13: maneuver: free time with duration_min_s = 5 > duration_max_s = 2, expected "
                      "duration_min_s <= duration_max_s"));
  // a weighted objective that weights nothing (line 14)
  CHECK_THAT(problems_of(head + "duration_s = 1.0\nobjective = \"weighted\"\nenergy_weight = 0.0\n"),
             Contains("line 14: maneuver.energy_weight, time_weight, smooth_weight and vibration_weight are all 0, "
                      "expected at least one > 0"));
  // a time weight with a fixed duration (line 15)
  CHECK_THAT(problems_of(head + "duration_s = 1.0\nobjective = \"weighted\"\nfree_duration = false\n"
                                "time_weight = 1.0\n"),
             Contains("line 15: maneuver.time_weight = 1 with a fixed duration, expected free_duration = true"));
  // one entry per actuator (line 13)
  CHECK_THAT(problems_of(head + "duration_s = 1.0\nactuator_weights = [1.0, 2.0]\n"),
             Contains("line 13: maneuver.actuator_weights has 2 entries, expected 1 (one per actuator)"));
  // a value the reader rejected is not reported again by the library (one problem)
  try {
    parse_design(head + "objective = \"time\"\nduration_min_s = -1.0\n", "t.toml");
    FAIL("the design loaded");
  } catch (const DesignError& e) {
    CHECK(e.problems().size() == 1);
    CHECK_THAT(e.what(), Contains("maneuver.duration_min_s = -1.0, must be > 0"));
  }
}

TEST_CASE("controller keys load, bad weights, horizons and names are reported", "[io]") {
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
             Contains("line 22: controller.weight_elastic = -1, must be >= 0 (the state weight Q must be "
                      "positive semidefinite)"));
  CHECK_THAT(problems_of(head + "horizon_s = 3.0\ninput_weights = [0.0]\n"),
             Contains("line 22: controller.input_weights: every entry must be > 0 (the input weight R must be "
                      "positive definite)"));
  CHECK_THAT(problems_of(head + "horizon_s = 0.5\n"),
             Contains("line 21: controller.horizon_s = 0.5, shorter than the maneuver (its loads act until 1 s)"));
  // Two actuators whose weights differ by more than 1e12: R would be singular to the LQR.
  const std::string two = kPaperBeam + acts + "[[actuator]]\nname = \"tip\"\ntype = \"thruster\"\nposition_m = 1.0\n" +
                          "direction = [0.0, 1.0]\n[controller]\nactuators = [\"hub\", \"tip\"]\nhorizon_s = 3.0\n";
  CHECK(problems_of(two + "input_weights = [1e-6, 1e6]\n").empty());
  CHECK_THAT(problems_of(two + "input_weights = [1e-7, 1e6]\n"),
             Contains("line 27: controller.input_weights spans 1e-07 to 1e+06, more than a factor 1e+12"));
  // A maneuver longer than the horizon is refused before anything runs.
  auto maneuver_then_controller = [&](const std::string& duration_keys) {
    return kPaperBeam + "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 0.5\nlimit = 1.0\n" +
           "[maneuver]\nactuators = [\"hub\"]\n" + duration_keys + "[maneuver.final]\ntheta_deg = 90.0\n" +
           "[controller]\nactuators = [\"hub\"]\n";
  };
  const std::string man = maneuver_then_controller("duration_s = 3.0\n");  // [controller] line 15
  CHECK(problems_of(man + "horizon_s = 3.0\n").empty());
  CHECK_THAT(problems_of(man + "horizon_s = 2.5\n"),
             Contains("line 17: controller.horizon_s = 2.5, shorter than the maneuver (maneuver.duration_s = 3)"));
  const std::string free = maneuver_then_controller("free_duration = true\nduration_min_s = 2.0\n");  // line 16
  CHECK(problems_of(free + "horizon_s = 3.0\n").empty());  // the optimizer may still choose longer: checked then
  CHECK_THAT(problems_of(free + "horizon_s = 1.5\n"),
             Contains("line 18: controller.horizon_s = 1.5, shorter than the maneuver (maneuver.duration_min_s = 2)"));
  // A rejected maneuver duration is reported once; the horizon is not compared with a value
  // the file does not hold (once the midpoint of the default duration bounds, 5.05 s).
  for (const char* bad : {"duration_s = 0\n", "duration_s = \"x\"\n"}) {
    const std::string problems = problems_of(maneuver_then_controller(bad) + "horizon_s = 5.0\n");
    CHECK_THAT(problems, Contains("line 12: maneuver.duration_s"));
    CHECK_THAT(problems, !Contains("horizon_s"));
  }
  // An actuator rejected for a bad field is not reported again, as unknown, where it is named.
  const std::string bad_hub = kPaperBeam +
                              "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 7.0\nlimit = 1.0\n" +
                              "[maneuver]\nactuators = [\"hub\"]\nduration_s = 3.0\n[maneuver.final]\ntheta_deg = 90.0\n" +
                              "[controller]\nactuators = [\"hub\"]\nhorizon_s = 3.0\n";
  const std::string hub_problems = problems_of(bad_hub);
  CHECK_THAT(hub_problems, Contains("line 8: actuator[1].position_m = 7.0, must be in [0, 1]"));
  CHECK_THAT(hub_problems, !Contains("is not an [[actuator]]"));
  // A controller that leaves out maneuver actuators names each one it misses.
  const std::string two_man = kPaperBeam + acts +
                              "[[actuator]]\nname = \"tip\"\ntype = \"thruster\"\nposition_m = 1.0\n"
                              "direction = [0.0, 1.0]\nlimit = 1.0\n[maneuver]\nactuators = [\"hub\", \"tip\"]\n"
                              "duration_s = 3.0\n[maneuver.final]\ntheta_deg = 90.0\n[controller]\nhorizon_s = 3.0\n"
                              "actuators = [\"hub\"]\n";
  CHECK_THAT(problems_of(two_man), Contains("must include every maneuver actuator (the feedback adds to their "
                                            "commands); \"tip\" is missing"));
  CHECK_THAT(problems_of(kPaperBeam + acts + "[controller]\nactuators = [\"rudder\"]\nhorizon_s = 3.0\n"),
             Contains("line 20: controller.actuators: \"rudder\" is not an [[actuator]] (known: 'hub')"));
}


TEST_CASE("[model] geometric_stiffening and [motion]: keys, defaults and every problem at once", "[io]") {
  const std::string beam = "[beam]\nlength_m = 10.0\nmass_kg = 12.0\nbending_stiffness_Nm2 = 14000.0\nreference_m = 0.0\n";
  const std::string sim = "[simulation]\nduration_s = 1.0\n";
  {
    const Design d = parse_design(beam + "[motion.theta]\ntype = \"spin_up\"\nfinal_rate_deg_s = 180.0\nramp_time_s = 2.0\n" + sim,
                                  "t.toml");
    CHECK(d.geometric_stiffening);  // the default for a design that does not say
    REQUIRE(d.motion);
    CHECK(d.motion->theta.kind() == MotionProfile::Kind::SpinUp);
    CHECK(d.motion->theta.at(3.0)(1) == Approx(M_PI));  // 180 deg/s, held after the ramp
    CHECK(d.motion->x.kind() == MotionProfile::Kind::Rest);
  }
  {
    const Design d = parse_design(beam + "[model]\ngeometric_stiffening = false\n[motion]\nhub_radius_m = 0.5\n"
                                         "[motion.theta]\ntype = \"table\"\ntimes_s = [0.0, 1.0]\nvalues_deg = [0.0, 90.0]\n"
                                         "rates_deg_s = [0.0, 180.0]\naccelerations_deg_s2 = [180.0, 180.0]\n" + sim,
                                  "t.toml");
    CHECK_FALSE(d.geometric_stiffening);
    REQUIRE(d.motion);
    CHECK(d.motion->hub_radius_m == 0.5);
    CHECK(d.motion->theta.at(1.0)(0) == Approx(M_PI / 2));
  }
  const std::string bad = problems_of(beam +
                                      "[motion.theta]\ntype = \"spin_up\"\nramp_time_s = 0.0\n"        // lines 6-8
                                      "[motion.x]\ntype = \"table\"\ntimes_s = [1.0, 2.0]\nvalues_m = [0.0, 1.0]\n"
                                      "rates_m_s = [0.0, 1.0]\naccelerations_m_s2 = [0.0, 0.0]\n"      // lines 9-14
                                      "[motion.y]\ntype = \"wobble\"\n" + sim);                         // lines 15-16
  CHECK_THAT(bad, Contains("motion.theta.final_rate_deg_s") && Contains("required"));
  CHECK_THAT(bad, Contains("line 8: motion.theta.ramp_time_s = 0.0, must be > 0"));
  CHECK_THAT(bad, Contains("motion.x.times_s") && Contains("the times must start at 0"));
  CHECK_THAT(bad, Contains("line 16: motion.y.type") && Contains("wobble"));
  CHECK_THAT(problems_of(beam + "[motion]\nhub_radius_m = 1.0\n" + sim), Contains("[motion] prescribes nothing"));
  CHECK_THAT(problems_of(beam + "[simulation]\nduration_s = 1.0\ncompare_stiffening = true\nnonlinear = false\n"
                                "[motion.theta]\ntype = \"spin_up\"\nfinal_rate_deg_s = 1.0\nramp_time_s = 1.0\n"),
             Contains("compare_stiffening = true needs nonlinear = true"));
}

TEST_CASE("elastic maneuver keys load and bad values are reported at their keys", "[io]") {
  const std::string act = "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 0.5\nlimit = 2.0\n";  // 5-9
  const std::string head = kPaperBeam + act + "[maneuver]\nactuators = [\"hub\"]\nduration_s = 1.0\n";  // 10-12
  const Design d = parse_design(head + "elastic = true\nelastic_modes = 2\nmodes_at_rest = \"all\"\n"
                                       "zero_end_commands = true\nvibration_weight = 3.0\ntip_deflection_limit_m = 0.05\n",
                                "t.toml");
  REQUIRE(d.maneuver);
  const ManeuverProblem& p = d.maneuver->problem;
  CHECK(p.elastic);
  CHECK(p.elastic_modes == 2);
  CHECK(p.modes_at_rest == ManeuverProblem::all_modes);
  CHECK(p.zero_end_commands);
  CHECK(p.w_vibration == 3.0);
  CHECK(p.tip_deflection_limit_m == 0.05);
  const Design plain = parse_design(head, "t.toml");
  CHECK_FALSE(plain.maneuver->problem.elastic);
  CHECK(plain.maneuver->problem.elastic_modes == ManeuverProblem::all_modes);
  CHECK_FALSE(plain.maneuver->problem.zero_end_commands);
  // the paper beam's model.noa is 6 (line 13 / 14)
  CHECK_THAT(problems_of(head + "elastic = true\nelastic_modes = 7\n"),
             Contains("line 14: maneuver.elastic_modes = 7, must be"));
  CHECK_THAT(problems_of(head + "elastic = true\nelastic_modes = 2\nmodes_at_rest = 3\n"),
             Contains("line 15: maneuver.modes_at_rest = 3, expected at most elastic_modes = 2"));
  CHECK_THAT(problems_of(head + "elastic_modes = 2\n"), Contains("line 13: maneuver.elastic_modes = 2 needs elastic = true"));
  CHECK_THAT(problems_of(head + "modes_at_rest = 1\n"), Contains("line 13: maneuver.modes_at_rest = 1 needs elastic = true"));
  CHECK_THAT(problems_of(head + "elastic = true\ntip_deflection_limit_m = 0\n"),
             Contains("line 14: maneuver.tip_deflection_limit_m = 0"));
}

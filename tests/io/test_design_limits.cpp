// Design files: the bounds a design is held to before any work (counts, file size,
// supported magnitudes, distinct output names, studies that could only fail later) and
// the form of the messages.
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

TEST_CASE("every shipped design loads", "[io]") {
  // the checks below must not refuse what designs/ ships (bang-bang, maneuvers, figures)
  int n = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(FREEFLEX_SOURCE_DIR) + "/designs")) {
    if (entry.path().extension() != ".toml") continue;
    INFO(entry.path().string());
    CHECK_NOTHROW(load_design(entry.path().string()));
    ++n;
  }
  CHECK(n >= 7);
}

TEST_CASE("counts derived from the design are bounded before any run", "[io]") {
  const std::string sim = kPaperBeam + kLoad + "[simulation]\n";  // [simulation] on line 14
  CHECK_THAT(problems_of(sim + "duration_s = 3.0\noutput_step_s = 1e-9\n"),
             Contains("line 16: simulation.output_step_s = 1e-09 with duration_s = 3 gives 3000000001 output rows; "
                      "at most 200000: raise output_step_s or shorten duration_s"));
  // at the limit: 199.999 s at 1 ms is 200000 rows, 200.001 s is 200002
  CHECK(problems_of(sim + "duration_s = 199.999\noutput_step_s = 0.001\n").empty());
  CHECK_THAT(problems_of(sim + "duration_s = 200.001\noutput_step_s = 0.001\n"),
             Contains("gives 200002 output rows; at most 200000"));
  CHECK_THAT(problems_of(sim + "duration_s = 3.0\ntrajectory_step_s = 1e-12\n"),
             Contains("line 16: simulation.trajectory_step_s = 1e-12 with duration_s = 3 gives 3000000000001 samples "
                      "of the zero-order motion; at most 1000000: raise trajectory_step_s or shorten duration_s"));
  CHECK_THAT(problems_of(sim + "duration_s = 5000.0\noutput_step_s = 0.5\n"),
             Contains("line 15: simulation.duration_s = 5000 with trajectory_step_s = 0.001 (the default) gives "
                      "5000001 samples of the zero-order motion"));
  // without the perturbation solution nothing samples the zero-order motion
  CHECK(problems_of(sim + "duration_s = 5000.0\noutput_step_s = 0.5\nperturbation = false\n").empty());
  CHECK_THAT(problems_of(sim + "duration_s = 1e12\n"),
             Contains("line 15: simulation.duration_s = 1e+12, must be within [1e-06, 1e+06] (the supported range)"));

  const std::string hub = "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 0.5\nlimit = 1.0\n";  // 14-18
  const std::string ctl = kPaperBeam + kLoad + hub + "[controller]\nactuators = [\"hub\"]\n";  // [controller] line 19
  CHECK(problems_of(ctl + "horizon_s = 3.0\n").empty());
  CHECK_THAT(problems_of(ctl + "horizon_s = 3.0\ngrid_step_s = 1e-9\n"),
             Contains("line 22: controller.grid_step_s = 1e-09 with horizon_s = 3 gives 3000000001 TV-LQR gain grid "
                      "points; at most 200000: raise grid_step_s or shorten horizon_s"));
  CHECK_THAT(problems_of(ctl + "horizon_s = 1e5\n"),
             Contains("line 21: controller.horizon_s = 100000 with grid_step_s = 0.005 (the default) gives 20000001 "
                      "TV-LQR gain grid points"));
  CHECK_THAT(problems_of(ctl + "horizon_s = 3.0\nsimulate_until_s = 1e6\n"),
             Contains("line 22: controller.simulate_until_s = 1e+06 with the fixed output step (no [simulation]) = "
                      "0.005 gives 200000001 output rows of the comparison runs; at most 200000"));
  CHECK_THAT(problems_of(ctl + "horizon_s = 3.0\nsimulate_until_s = 10.0\n[simulation]\nduration_s = 3.0\n"
                               "output_step_s = 0.01\ntrajectory_step_s = 1e-6\n"),
             Contains("line 22: controller.simulate_until_s = 10 with simulation.trajectory_step_s = 1e-06 gives "
                      "10000001 samples of the zero-order motion; at most 1000000"));
  const std::string act = "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 0.5\n";
  CHECK_THAT(problems_of(kPaperBeam + act + "[maneuver]\nactuators = [\"hub\"]\nduration_s = 3.0\nintervals = 6000\n"),
             Contains("maneuver.intervals = 6000, must be a whole number in [1, 5000]"));
}

TEST_CASE("only a regular file of at most 1 MiB is read as a design", "[io]") {
  CHECK_THROWS_WITH(load_design("/dev/zero"), Contains("design '/dev/zero': is not a regular file"));
  const std::string dir = std::filesystem::temp_directory_path().string();
  CHECK_THROWS_WITH(load_design(dir), Contains("design '" + dir + "': is a directory"));
  // a good design padded with a comment to exactly 1 MiB loads; one byte more does not
  const std::string path = dir + "/freeflex_io_size_" + std::to_string(::getpid()) + ".toml";
  const std::size_t limit = design_limits::kMaxFileBytes;
  const std::string text = std::string(kGood) + "#" + std::string(limit - std::strlen(kGood) - 1, 'x');
  REQUIRE(text.size() == limit);
  std::ofstream(path, std::ios::binary) << text;
  CHECK_NOTHROW(load_design(path));
  std::ofstream(path, std::ios::binary) << text << 'x';
  CHECK_THROWS_WITH(load_design(path), Contains("is larger than 1048576 bytes (1 MiB)"));
  std::filesystem::remove(path);
  CHECK_THROWS_AS(parse_design(text + "x", "t.toml"), DesignError);
}

namespace {
// The paper's moment pulse with a hub torque, a TV-LQR and bang-bang rotations.
const std::string kTorqueLoad =  // lines 5-12
    "[[load]]\nname = \"M\"\ntype = \"torque\"\nposition_m = 0.5\n"
    "[load.profile]\ntype = \"steps\"\ntimes_s = [0.0, 0.5, 1.0]\nvalues = [1.0, -1.0]\n";
std::string suppression(const std::string& hub_position = "0.5", const std::string& modes = "[1, 2]",
                        const std::string& load = kTorqueLoad) {
  return kPaperBeam + load + "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = " + hub_position +
         "\nlimit = 1.0\n"                                         // 13-17
         "[controller]\nactuators = [\"hub\"]\nhorizon_s = 3.0\n"  // 18-20
         "[bang_bang]\nactuator = \"hub\"\nmodes = " +
         modes + "\n";  // 21-23
}
std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  REQUIRE(at != std::string::npos);
  return s.replace(at, from.size(), to);
}
}  // namespace

TEST_CASE("bang-bang studies that could only fail after the other runs are refused up front", "[io]") {
  const Design d = parse_design(suppression(), "t.toml");
  REQUIRE(d.bang_bang);
  CHECK(d.bang_bang->modes == std::vector<int>{1, 2});
  CHECK_THAT(problems_of(suppression("0.2")),
             Contains("line 22: bang_bang.actuator: \"hub\" acts at position_m = 0.2, but o is at 0.5 m from the left "
                      "end; the bang-bang torque must act at o"));
  // a torque at the centre of a uniform beam excites the antisymmetric modes only: 3 of 6
  CHECK_THAT(problems_of(suppression("0.5", "[0, 1, 2, 3, 4]")),
             Contains("line 23: bang_bang.modes contains 4, but \"hub\" excites only 3 elastic modes with model.noa = "
                      "6; each k must be at most 3"));
  CHECK(problems_of(suppression("0.5", "[0, 1, 2, 3, 4]") + "[model]\nnoa = 8\n").empty());
  CHECK_THAT(problems_of(suppression("0.5", "[1, 2, 1]")),
             Contains("line 23: bang_bang.modes lists 1 twice; each k at most once"));
  CHECK_THAT(problems_of(suppression("0.5", "[1]", replaced(kTorqueLoad, "[1.0, -1.0]", "[0.0, 0.0]"))),
             Contains("line 22: [bang_bang] flies the nominal rotation, but no [[load]] turns the beam"));
  CHECK_THAT(problems_of(suppression("0.5", "[1]", replaced(kTorqueLoad, "[1.0, -1.0]", "[-1.0, 1.0]"))),
             Contains("line 22: [bang_bang] flies the nominal rotation, but the loads turn the beam by a negative "
                      "angle by controller.simulate_until_s = 3 s"));
  // a force through o does not turn the beam either; one at a tip does
  CHECK_THAT(problems_of(suppression("0.5", "[1]", kLoad)), Contains("no [[load]] turns the beam"));
  CHECK(problems_of(suppression("0.5", "[1]", replaced(kLoad, "position_m = 0.5", "position_m = 1.0"))).empty());
  CHECK_THAT(problems_of(replaced(suppression("0.4"), "bending_stiffness_Nm2 = 1.0\n",
                                  "bending_stiffness_Nm2 = 1.0\nreference_m = 0.4\n")),
             Contains("[bang_bang] needs o at the mass centre (0.5 m from the left end), but beam.reference_m puts it "
                      "at 0.4 m"));
}

TEST_CASE("inputs accepted before but meaningless or fatal later are refused", "[io]") {
  const std::string act = "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 0.5\nlimit = 1.0\n";  // 5-9
  const std::string man = kPaperBeam + act +
                          "[maneuver]\nactuators = [\"hub\"]\nduration_s = 3.0\n"    // 10-12
                          "[maneuver.final]\ntheta_deg = 90.0\n[maneuver.ipopt]\n";  // 13-15
  CHECK_THAT(problems_of(man + "bound_push = nan\n"),
             Contains("line 16: maneuver.ipopt.bound_push = nan, must be a finite number"));
  // the factorization is chosen by [maneuver] linear_solver; Ipopt's own key would let
  // "ma97" abort the process (no HSL library) and "mumps" contradict the freeflex key
  for (const char* solver : {"ma97", "mumps", "ma27"})
    CHECK_THAT(problems_of(man + "linear_solver = \"" + solver + "\"\n"),
               Contains("line 16: maneuver.ipopt.linear_solver = \"" + std::string(solver) +
                        "\": choose the factorization with maneuver.linear_solver = \"ldlt\" or \"mumps\""));
  const std::string with_solver = kPaperBeam + act + "[maneuver]\nactuators = [\"hub\"]\nduration_s = 3.0\n";
  CHECK(problems_of(with_solver + "linear_solver = \"mumps\"\n").empty());
  CHECK_THAT(problems_of(with_solver + "linear_solver = \"ma27\"\n"),
             Contains("line 13: maneuver.linear_solver = \"ma27\""));
  CHECK_THAT(problems_of(man + "linear_system_scaling = \"MC19\"\n"),
             Contains("line 16: maneuver.ipopt.linear_system_scaling = \"MC19\", must be \"none\" or \"slack-based\""));
  // Ipopt's own log file: a plain name in the output directory, not a path anywhere else
  CHECK(problems_of(man + "output_file = \"ipopt.out\"\n").empty());
  for (const char* bad : {"../ipopt.out", "/tmp/ipopt.out", ".hidden", ""})
    CHECK_THAT(problems_of(man + "output_file = \"" + bad + "\"\n"),
               Contains("line 16: maneuver.ipopt.output_file = \"" + std::string(bad) +
                        "\", must be a file name of 1 to 64 letters"));
  CHECK_THAT(problems_of(man + "output_file = \"trajectory.csv\"\n"),
             Contains("line 16: maneuver.ipopt.output_file = \"trajectory.csv\" writes trajectory.csv, which "
                      "[maneuver] writes too"));
  CHECK_THAT(problems_of(replaced(man, "actuators = [\"hub\"]", "actuators = [\"hub\", \"hub\"]")),
             Contains("line 11: maneuver.actuators lists \"hub\" more than once; each actuator at most once"));
  CHECK_THAT(problems_of(kPaperBeam + kLoad +
                         "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 0.5\n"
                         "[controller]\nactuators = [\"hub\", \"hub\", \"hub\"]\nhorizon_s = 3.0\n"),
             Contains("line 19: controller.actuators lists \"hub\" more than once; each actuator at most once"));
  // f15b: more damping ratios than elastic modes
  CHECK_THAT(problems_of(kPaperBeam + "[damping]\nratios = [0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1]\n"),
             Contains("line 6: damping.ratios has 7 entries, but the model has 6 elastic modes (model.noa = 6); at "
                      "most 6"));
  CHECK(problems_of(kPaperBeam + "[damping]\nratios = [0.1, 0.1, 0.1, 0.1, 0.1, 0.1]\n").empty());
  // at most 100 spin rates (each costs two eigenproblems of the model's size)
  std::string rates = "0.0";
  for (int i = 1; i < 100; ++i) rates += ", 1.0";
  CHECK(problems_of(kPaperBeam + "[free_vibration]\nspin_rates_deg_s = [" + rates + "]\n").empty());
  CHECK_THAT(problems_of(kPaperBeam + "[free_vibration]\nspin_rates_deg_s = [" + rates + ", 2.0]\n"),
             Contains("line 6: free_vibration.spin_rates_deg_s has 101 entries; at most 100"));
  CHECK_THAT(problems_of(kPaperBeam + replaced(kLoad, "[0.0, 1.0]", "[0.0, 0.0]")),
             Contains("line 9: load[1].direction = [0, 0] has length 0, must have a length in [1e-06, 1e+06]"));
  CHECK_THAT(problems_of(kPaperBeam + replaced(kLoad, "[0.0, 0.5, 1.0]", "[5.0, 6.0, 7.0]") +
                         "[simulation]\nduration_s = 3.0\n"),
             Contains("line 15: simulation.duration_s = 3 ends before any load acts (the first at 5 s)"));
  CHECK_THAT(problems_of(kPaperBeam + act + "[controller]\nactuators = [\"hub\"]\nhorizon_s = 3.0\n"),
             Contains("line 11: [controller] needs a nominal motion whose vibration it suppresses"));
  const std::string ctl = kPaperBeam + kLoad + act + "[controller]\nactuators = [\"hub\"]\nhorizon_s = 3.0\n";  // 19-21
  CHECK_THAT(problems_of(ctl + "simulate_until_s = 0.1\n"),
             Contains("line 22: controller.simulate_until_s = 0.1 is shorter than horizon_s = 3"));
  CHECK_THAT(problems_of(ctl + "simulate_until_s = 4.0\n[simulation]\nduration_s = 6.0\noutput_step_s = 5.0\n"),
             Contains("line 22: controller.simulate_until_s = 4 is shorter than simulation.output_step_s = 5"));
}

TEST_CASE("output files must have distinct names", "[io]") {
  const std::string fv = kPaperBeam + "[free_vibration]\ntable_name = \"shape\"\n";  // [free_vibration] line 5
  CHECK_THAT(problems_of(fv + "[[free_vibration.mode_shape]]\nname = \"shape\"\nmode = 4\n"),
             Contains("line 8: free_vibration.mode_shape[1].name = \"shape\" writes shape.csv, which "
                      "free_vibration.table_name = \"shape\" (line 6) writes too; output files must have distinct "
                      "names"));
  CHECK_THAT(problems_of(kPaperBeam + "[free_vibration]\n[[free_vibration.mode_shape]]\nname = \"a\"\nmode = 4\n"
                                      "[[free_vibration.mode_shape]]\nname = \"a\"\nmode = 2\n"),
             Contains("line 10: free_vibration.mode_shape[2].name = \"a\" writes a.csv, a.gp, a.png, which "
                      "free_vibration.mode_shape[1].name = \"a\" (line 7) writes too"));
  const std::string sim = kPaperBeam + kLoad + "[simulation]\nduration_s = 3.0\n";  // [simulation] line 14
  CHECK_THAT(problems_of(sim + "rigid_figure = \"f\"\nelastic_figure = \"f\"\n"),
             Contains("line 17: simulation.elastic_figure = \"f\" writes f.gp, f.png, which simulation.rigid_figure = "
                      "\"f\" (line 16) writes too"));
  // against a default name and a name a study fixes
  CHECK_THAT(problems_of(sim + "elastic_figure = \"rigid_motion\"\n"),
             Contains("line 16: simulation.elastic_figure = \"rigid_motion\" writes rigid_motion.gp, rigid_motion.png, "
                      "which simulation.rigid_figure = \"rigid_motion\" (the default) writes too"));
  CHECK_THAT(problems_of(sim + "[free_vibration]\ntable_name = \"nonlinear\"\n"),
             Contains("line 17: free_vibration.table_name = \"nonlinear\" writes nonlinear.csv, which [simulation] "
                      "writes too"));
  CHECK(problems_of(sim + "perturbation = true\nnonlinear = false\n[free_vibration]\ntable_name = \"nonlinear\"\n")
            .empty());
}

TEST_CASE("absurd magnitudes are outside the supported range", "[io]") {
  auto beam = [](const std::string& L, const std::string& m, const std::string& ei) {
    return "[beam]\nlength_m = " + L + "\nmass_kg = " + m + "\nbending_stiffness_Nm2 = " + ei + "\n";
  };
  CHECK(problems_of(beam("1e4", "1e9", "1e12")).empty());
  CHECK(problems_of(beam("1e-3", "1e-6", "1e-6")).empty());
  CHECK_THAT(problems_of(beam("1e300", "1.0", "1.0")),
             Contains("line 2: beam.length_m = 1e+300, must be within [0.001, 10000] (the supported range)"));
  CHECK_THAT(problems_of(beam("1.0", "1e308", "1.0")),
             Contains("line 3: beam.mass_kg = 1e+308, must be within [1e-06, 1e+09] (the supported range)"));
  CHECK_THAT(problems_of(beam("1.0", "1e-300", "1.0")), Contains("line 3: beam.mass_kg = 1e-300, must be within"));
  CHECK_THAT(problems_of(beam("1.0", "1.0", "1e13")), Contains("line 4: beam.bending_stiffness_Nm2 = 1e+13"));
  // o within L/1000 of an end
  CHECK_THAT(problems_of(beam("1.0", "1.0", "1.0") + "reference_m = 1e-12\n"),
             Contains("line 5: beam.reference_m = 1e-12, must be 0 or 1 (o at an end: a cantilever clamped at o) or "
                      "within [0.001, 0.999] (the supported range)"));
  CHECK(problems_of(beam("1.0", "1.0", "1.0") + "reference_m = 0.001\n").empty());
  CHECK_THAT(problems_of(kPaperBeam + replaced(kLoad, "[0.0, 1.0]", "[0.0, 1e300]")),
             Contains("line 9: load[1].direction contains 1e+300, each entry must be within [-1e+06, 1e+06]"));
  CHECK_THAT(problems_of(kPaperBeam + replaced(kLoad, "[1.0, -1.0]", "[1e300, -1.0]")),
             Contains("line 13: load[1].profile.values contains 1e+300, each entry must be within [-1e+12, 1e+12]"));
  CHECK_THAT(problems_of(kPaperBeam + replaced(kLoad, "[0.0, 0.5, 1.0]", "[0.0, nan, 1.0]")),
             Contains("line 12: load[1].profile.times_s contains nan, each entry must be a finite number"));
  CHECK_THAT(problems_of(kPaperBeam + "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 0.5\n"
                                      "limit = 1e13\n"),
             Contains("line 9: actuator[1].limit = 1e+13, must be at most 1e+12"));
  // a mass per length within its range can still make a beam too heavy or too light
  CHECK_THAT(problems_of("[beam]\nlength_m = 10000.0\nmass_per_length_kg_m = 1e6\nbending_stiffness_Nm2 = 1.0\n"),
             Contains("line 3: beam: the mass per length gives a beam of 1e+10 kg; it must be within [1e-06, 1e+09]"));
  CHECK_THAT(problems_of("[[beam.segment]]\nlength_m = 0.001\nmass_per_length_kg_m = 1e-5\n"
                         "bending_stiffness_Nm2 = 1.0\n"),
             Contains("beam: the mass per length gives a beam of 1e-08 kg"));
  CHECK_THAT(problems_of("[[beam.segment]]\nlength_m = 1.0\nmass_per_length_kg_m = 1e-12\n"
                         "bending_stiffness_Nm2 = 1.0\n"),
             Contains("line 3: beam.segment[1].mass_per_length_kg_m = 1e-12, must be within [1e-06, 1e+06]"));
  CHECK_THAT(
      problems_of("[[beam.segment]]\nlength_m = 0.5\nmass_per_length_kg_m = 1e12\nbending_stiffness_Nm2 = 1.0\n"
                  "[[beam.segment]]\nlength_m = 0.5\nmass_per_length_kg_m = 1.0\nbending_stiffness_Nm2 = 1e-12\n"),
      Contains("line 3: beam.segment[1].mass_per_length_kg_m = 1e+12, must be within [1e-06, 1e+06]"));
}

TEST_CASE("messages: one problem per mistake, shortest numbers, what an array holds", "[io]") {
  // a bad [[load]] is not also a missing one
  try {
    parse_design(
        kPaperBeam + replaced(kLoad, "position_m = 0.5", "position_m = 1.5") + "[simulation]\nduration_s = 1.0\n",
        "t.toml");
    FAIL("expected a DesignError");
  } catch (const DesignError& e) {
    CHECK(e.problems().size() == 1);
    CHECK_THAT(e.what(), Contains("line 8: load[1].position_m = 1.5"));
  }
  CHECK_THAT(problems_of("[beam]\nlength_m = -0.1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n"),
             Contains("line 2: beam.length_m = -0.1, must be > 0"));
  CHECK_THAT(problems_of(kPaperBeam + kLoad + "[simulation]\nduration_s = 0.001\noutput_step_s = 0.002\n"),
             Contains("line 16: simulation.output_step_s = 0.002 exceeds duration_s = 0.001, expected "
                      "output_step_s <= duration_s"));  // the library's check, at the key
  // a duration below a microsecond, down to 1e-300 (which CVODE cannot start on), is refused
  CHECK_THAT(problems_of(kPaperBeam + kLoad + "[simulation]\nduration_s = 1e-300\n"),
             Contains("line 15: simulation.duration_s = 1e-300, must be within [1e-06, 1e+06] (the supported range)"));
  CHECK_THAT(problems_of(kPaperBeam + replaced(kLoad, "[0.0, 0.5, 1.0]", "[[0.0], [0.5], [1.0]]")),
             Contains("line 12: load[1].profile.times_s contains [0.0], must be an array of numbers (not of arrays)"));
}

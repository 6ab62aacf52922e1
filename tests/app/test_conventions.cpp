// The library's conventions, checked across layers: every Options struct's defaults are
// valid, and every public enum that files and summaries use round-trips through its
// names, which are the spellings design files take.
#include <catch2/catch.hpp>

#include <regex>
#include <set>

#include "freeflex/freeflex.hpp"

using namespace freeflex;
using Catch::Contains;

namespace {

/// Every name of E: lower case words joined by '_', distinct, and to_string / from_string
/// / parse_enum inverse to each other.
template <class E>
void check_names() {
  INFO(EnumNames<E>::what);
  std::set<std::string> seen;
  for (const auto& [value, name] : EnumNames<E>::names) {
    INFO(name);
    CHECK(std::regex_match(std::string(name), std::regex("[a-z][a-z0-9]*(_[a-z0-9]+)*")));
    CHECK(seen.insert(name).second);
    CHECK(std::string(to_string(value)) == name);
    CHECK(from_string<E>(name) == value);
    CHECK(parse_enum<E>(name) == value);
  }
  CHECK(enum_names<E>().size() == EnumNames<E>::names.size());
  CHECK_FALSE(parse_enum<E>("no_such_name").has_value());
  CHECK_THROWS_WITH(from_string<E>("no_such_name"),
                    Contains("unknown " + std::string(EnumNames<E>::what) + " 'no_such_name', expected one of"));
}

const std::string kBeam = "[beam]\nlength_m = 1.0\nmass_kg = 1.0\nbending_stiffness_Nm2 = 1.0\n";

}  // namespace

TEST_CASE("every Options struct's defaults are valid", "[api]") {
  CHECK_NOTHROW(validate(IntegratorOptions{}));
  CHECK(problems(IntegratorOptions{}).empty());
  CHECK_NOTHROW(validate(SimulationOptions{}));
  CHECK(problems(SimulationOptions{}).empty());
  CHECK_NOTHROW(validate(TrajoptOptions{}));
  CHECK(problems(TrajoptOptions{}).empty());
  CHECK_NOTHROW(validate(CareOptions{}));
  CHECK_NOTHROW(validate(TvlqrOptions{}));
  CHECK_NOTHROW(validate(ClosedLoopOptions{}));
  CHECK_NOTHROW(validate(SwitchTimeOptions{}));
  CHECK_NOTHROW(validate(SuppressionOptions{}));
  CHECK_NOTHROW(validate(RunOptions{}));  // no directory: the studies run, nothing is written
  CHECK_NOTHROW(validate(PlotOptions{}));
  // and each validate() does reject a setting out of range, naming it
  auto rejects = [](auto options, auto spoil, const std::string& expect) {
    spoil(options);
    CHECK_THROWS_WITH(validate(options), Contains(expect));
  };
  rejects(IntegratorOptions{}, [](auto& o) { o.rtol = -1.0; }, "rtol = -1");
  rejects(SimulationOptions{}, [](auto& o) { o.output_step_s = 5.0; }, "output_step_s = 5 exceeds duration_s = 3");
  rejects(TrajoptOptions{}, [](auto& o) { o.intervals = 0; }, "intervals = 0");
  rejects(CareOptions{}, [](auto& o) { o.max_newton_iterations = -1; }, "max_newton_iterations");
  rejects(TvlqrOptions{}, [](auto& o) { o.grid_step_s = 0.0; }, "grid_step_s = 0");
  rejects(ClosedLoopOptions{}, [](auto& o) { o.output_step_s = -1.0; }, "output_step_s = -1");
  rejects(SwitchTimeOptions{}, [](auto& o) { o.starts = 0; }, "starts");
  rejects(SuppressionOptions{}, [](auto& o) { o.tvlqr.rtol = 0.0; }, "rtol");
  rejects(RunOptions{}, [](auto& o) { o.out_dir = std::string("a\0b", 3); }, "out_dir");
  rejects(PlotOptions{}, [](auto& o) { o.timeout_s = -1.0; }, "timeout_s = -1");
  rejects(RunOptions{}, [](auto& o) { o.plot.timeout_s = 1e9; }, "timeout_s = 1e+09");
  rejects(IntegratorOptions{}, [](auto& o) { o.max_total_steps = -1; }, "max_total_steps = -1");
  rejects(SwitchTimeOptions{}, [](auto& o) { o.max_steps_per_simulation = -1; }, "max_steps_per_simulation");
  rejects(SwitchTimeOptions{}, [](auto& o) { o.max_total_steps = -1; }, "max_total_steps = -1");
  rejects(SwitchTimeOptions{}, [](auto& o) { o.simulations_per_unknown = 0; }, "simulations_per_unknown = 0");
  CHECK_NOTHROW(validate(DiscretizeOptions{}));
  CHECK_NOTHROW(validate(PlantOptions{}));
  CHECK_NOTHROW(validate(SampledLoopOptions{}));
  CHECK_NOTHROW(validate(SweepExecution{}));
  rejects(DiscretizeOptions{}, [](auto& o) { o.integrator.rtol = -1.0; }, "rtol = -1");
  rejects(PlantOptions{}, [](auto& o) { o.delay_s = -0.1; }, "delay_s = -0.1");
  rejects(SampledLoopOptions{}, [](auto& o) { o.sample_rate_hz = 0.0; }, "sample_rate_hz = 0");
  rejects(SweepExecution{}, [](auto& o) { o.ranks = 2; }, "gather");
}

TEST_CASE("every public enum round-trips through its names", "[api]") {
  check_names<TimeProfile::Kind>();
  check_names<ForceElement::Type>();
  check_names<IntegratorOptions::Method>();
  check_names<IntegrationStatus>();
  check_names<SimulationOptions::Variables>();
  check_names<Transcription>();
  check_names<LinearSolver>();
  check_names<TrajoptStatus>();
  check_names<CareResult::Status>();
  check_names<TvlqrResult::Status>();
  check_names<TvlqrOptions::NewtonSolver>();
  check_names<Sensor::Type>();
  check_names<KalmanResult::Status>();
  check_names<SampledLoopOptions::Feedback>();
  check_names<SweepParameter::Name>();
  check_names<SweepParameter::Kind>();
  check_names<SwitchTimeResult::Status>();
  check_names<SwitchTimeOptions::Refine>();
  check_names<SuppressionResult::Status>();
  check_names<SuppressionPhase>();
  check_names<StudyStatus>();
  check_names<PlotResult::Status>();
}

TEST_CASE("enum names are the spellings design files take", "[api][io]") {
  const std::string actuators =
      "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 0.5\nlimit = 1.0\n"
      "[maneuver]\nactuators = [\"hub\"]\nduration_s = 1.0\n";
  for (const auto& [value, name] : EnumNames<Transcription>::names) {
    const Design d = parse_design(kBeam + actuators + "transcription = \"" + name + "\"\n", "t.toml");
    CHECK(d.maneuver->options.transcription == value);
  }
  for (const auto& [value, name] : EnumNames<LinearSolver>::names) {
    const Design d = parse_design(kBeam + actuators + "linear_solver = \"" + name + "\"\n", "t.toml");
    CHECK(d.maneuver->options.linear_solver == value);
  }
  const std::string load = "[[load]]\nname = \"F\"\ntype = \"torque\"\nposition_m = 0.5\n[load.profile]\n";
  for (const auto& [value, name] : EnumNames<TimeProfile::Kind>::names) {
    const std::string profile = value == TimeProfile::Kind::Steps ? "values = [1.0]\n" : "values = [1.0, 1.0]\n";
    const Design d = parse_design(kBeam + load + "type = \"" + name + "\"\ntimes_s = [0.0, 1.0]\n" + profile, "t.toml");
    CHECK(d.loads.at(0).profile.kind() == value);
  }
  for (const auto& [value, name] : EnumNames<ForceElement::Type>::names) {
    const std::string direction = value == ForceElement::Type::Torque ? "" : "direction = [0.0, 1.0]\n";
    const Design d = parse_design(kBeam + "[[actuator]]\nname = \"a\"\ntype = \"" + name + "\"\nposition_m = 0.5\n" +
                                      direction,
                                  "t.toml");
    CHECK(d.actuators.at(0).element.type == value);
  }
  const std::string simulation = load + "type = \"steps\"\ntimes_s = [0.0, 1.0]\nvalues = [1.0]\n[simulation]\nduration_s = 2.0\n";
  for (const auto& [value, name] : EnumNames<IntegratorOptions::Method>::names) {
    const Design d = parse_design(kBeam + simulation + "method = \"" + name + "\"\n", "t.toml");
    CHECK(d.simulation->options.integrator.method == value);
  }
  for (const auto& [value, name] : EnumNames<SimulationOptions::Variables>::names) {
    const bool rest = value == SimulationOptions::Variables::RestModes;  // the full model's only
    const Design d = parse_design(kBeam + simulation + "full_model_variables = \"" + name + "\"\n" +
                                      (rest ? "" : "first_order_variables = \"" + std::string(name) + "\"\n"),
                                  "t.toml");
    CHECK(d.simulation->options.full_variables == value);
    if (!rest) CHECK(d.simulation->options.first_order_variables == value);
  }
  for (const auto& [value, name] : EnumNames<SimulationOptions::FirstOrderSolver>::names) {
    const Design d = parse_design(kBeam + simulation + "first_order_solver = \"" + name + "\"\n", "t.toml");
    CHECK(d.simulation->options.first_order_solver == value);
  }
}

TEST_CASE("summary.json spells enum values as design files do", "[api][io]") {
  const Design d = parse_design(kBeam +
                                    "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 0.5\nlimit = 1.0\n"
                                    "[maneuver]\nactuators = [\"hub\"]\nduration_s = 1.0\n[maneuver.final]\n"
                                    "theta_deg = 10.0\n",
                                "t.toml");
  RunResult run;
  run.status = StudyStatus::Failed;
  run.message = "maneuver optimization did not succeed (max_iterations): ...";
  ManeuverStudyResult m;
  m.status = StudyStatus::Failed;
  m.trajopt.status = TrajoptStatus::MaxIterations;
  m.trajopt.transcription = Transcription::HermiteSimpsonCompressed;
  run.maneuver = m;
  const nlohmann::ordered_json j = summary_json(d, run);
  CHECK(j["status"] == "failed");
  CHECK(j["message"] == run.message);
  CHECK(j["studies"]["maneuver"]["status"] == "max_iterations");
  CHECK(j["studies"]["maneuver"]["transcription"] == "hermite_simpson_compressed");
  // the simulation's integrator and variables
  SimulationStudyResult sim;
  sim.method = IntegratorOptions::Method::Verner98;
  sim.full_variables = SimulationOptions::Variables::RestModes;
  sim.nonlinear = SimulationStudyResult::Solution{};
  sim.perturbation = SimulationStudyResult::Solution{};
  run.simulation = sim;
  const nlohmann::ordered_json k = summary_json(d, run);
  CHECK(k["studies"]["simulation"]["method"] == "verner98");
  CHECK(k["studies"]["simulation"]["nonlinear"]["variables"] == "rest_modes");
  CHECK(k["studies"]["simulation"]["perturbation"]["first_order_variables"] == "modal");
}

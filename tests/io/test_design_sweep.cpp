// [[sensor]], [lqg] and [sweep]: a good sweep loads; bad sweep input (empty ranges,
// negative deviations, unknown parameters, missing sections) is reported with key and
// line before any sample runs.
#include <catch2/catch.hpp>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "freeflex/app/sweep.hpp"
#include "freeflex/io/design.hpp"
#include "support/designs.hpp"

using namespace freeflex;
using namespace freeflex_test;
using Catch::Contains;

namespace {

std::string small_sweep() {
  std::ifstream in(std::string(FREEFLEX_SOURCE_DIR) + "/tests/data/sweep_small.toml");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// The small sweep with its [sweep] section (the file's last part) replaced.
std::string with_sweep(const std::string& sweep) {
  const std::string text = small_sweep();
  return text.substr(0, text.find("[sweep]")) + sweep;
}

}  // namespace

TEST_CASE("sweep designs: the test sweep and the shipped sweep load", "[io][sweep]") {
  const Design d = parse_design(small_sweep(), "t.toml");
  REQUIRE(d.sweep);
  CHECK(d.sweep->samples == 12);
  CHECK(d.sweep->total_samples() == 24);  // times the damping grid's 2 points
  REQUIRE(d.sweep->parameters.size() == 4);
  CHECK(d.sweep->parameters[2].kind == SweepParameter::Kind::Grid);
  const Design s = load_design(std::string(FREEFLEX_SOURCE_DIR) + "/designs/sweep_slew.toml");
  REQUIRE(s.sweep);
  CHECK(s.sweep->total_samples() == 1000);
  // grid values walk the grid in sample order; draws stay inside their ranges
  for (long i = 0; i < 24; ++i) {
    const std::vector<double> v = sweep_sample_values(*d.sweep, i);
    CHECK(v[2] == (i < 12 ? 0.0 : 0.02));
    CHECK((v[0] >= 0.9 && v[0] <= 1.1));
    CHECK((v[3] >= 0.0 && v[3] <= 0.005));
  }
  CHECK(sweep_sample_values(*d.sweep, 7) == sweep_sample_values(*d.sweep, 7));  // a function of (seed, index)
  CHECK(sweep_sample_values(*d.sweep, 7) != sweep_sample_values(*d.sweep, 8));
}

TEST_CASE("sweep designs: bad input names key and line before any sample runs", "[io][sweep]") {
  const std::string head = "[sweep]\nsamples = 10\nrequirement_energy_J = 1e-5\n";
  const std::string text = small_sweep();
  const int line0 = static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(text.find("[sweep]")), '\n')) + 1;
  auto at = [&](int offset) { return "line " + std::to_string(line0 + offset) + ": "; };
  // an empty range
  CHECK_THAT(problems_of(with_sweep(head + "[sweep.delay_s]\ndistribution = \"uniform\"\nmin = 0.02\nmax = 0.0\n")),
             Contains(at(6) + "sweep.delay_s.min = 0.02, max = 0: an empty range; expected min < max"));
  CHECK_THAT(problems_of(with_sweep(head + "[sweep.mass_scale]\ndistribution = \"grid\"\nmin = 1.1\nmax = 1.1\npoints = 3\n")),
             Contains("an empty range; expected min < max"));
  // a negative deviation
  CHECK_THAT(problems_of(with_sweep(head + "[sweep.mass_scale]\ndistribution = \"normal\"\nmean = 1.0\nstd = -0.1\n")),
             Contains(at(6) + "sweep.mass_scale.std = -0.1, must be > 0 (a standard deviation)"));
  // a parameter that does not exist
  CHECK_THAT(problems_of(with_sweep(head + "[sweep.stiffness]\ndistribution = \"uniform\"\nmin = 0.9\nmax = 1.1\n")),
             Contains("unknown key 'sweep.stiffness'"));
  CHECK_THAT(problems_of(with_sweep(head + "[sweep.stiffness]\ndistribution = \"uniform\"\nmin = 0.9\nmax = 1.1\n")),
             Contains("bending_stiffness_scale"));  // the allowed names are listed
  // values outside what the parameter means
  CHECK_THAT(problems_of(with_sweep(head + "[sweep.delay_s]\ndistribution = \"uniform\"\nmin = -0.01\nmax = 0.02\n")),
             Contains(at(5) + "sweep.delay_s.min = -0.01, must be in [0, 10] (delay_s is seconds)"));
  CHECK_THAT(problems_of(with_sweep(head + "[sweep.bending_stiffness_scale]\ndistribution = \"normal\"\nmean = 1.0\nstd = 0.3\n")),
             Contains("mean - 5 std = -0.5 falls below 0"));
  CHECK_THAT(problems_of(with_sweep(head + "[sweep.mass_scale]\ndistribution = \"uniform\"\nmean = 1.0\nmin = 0.9\nmax = 1.1\n")),
             Contains("sweep.mass_scale.mean does not apply to distribution = \"uniform\""));
  // nothing varied, no samples, no requirement, every problem at once
  const std::string all = problems_of(with_sweep("[sweep]\nsamples = 0\nfeedback = \"lqg\"\n"));
  CHECK_THAT(all, Contains(at(1) + "sweep.samples = 0"));
  CHECK_THAT(all, Contains("sweep.requirement_energy_J is required"));
  CHECK_THAT(all, Contains("[sweep] varies nothing"));
  CHECK_THAT(all, Contains("feedback = \"lqg\" needs an [lqg] section"));
}

TEST_CASE("sensor and lqg designs: keys and problems", "[io][sweep]") {
  const std::string base = small_sweep().substr(0, small_sweep().find("[sweep]"));
  const Design d = parse_design(base + "[[sensor]]\nname = \"g\"\ntype = \"gyro_rate\"\nnoise_density = 1e-5\n"
                                       "[[sensor]]\nname = \"s\"\ntype = \"strain\"\nposition_m = 0.25\nnoise_density = 1e-5\n"
                                       "[lqg]\nsample_rate_hz = 500\nprocess_noise_density = [0.002]\ndelay_s = 0.004\n"
                                       "delay_known = true\n",
                                "t.toml");
  REQUIRE(d.sensors.size() == 2);
  CHECK(d.sensors[1].type == Sensor::Type::Strain);
  CHECK(d.sensors[1].position_m == 0.25);
  REQUIRE(d.lqg);
  CHECK(d.lqg->plant.delay_s == 0.004);
  CHECK(d.lqg->process_noise_density(0) == 0.002);
  const std::string bad = problems_of(base + "[[sensor]]\nname = \"s\"\ntype = \"strain\"\nnoise_density = 0\n"
                                             "[lqg]\nsample_rate_hz = 500\nprocess_noise_density = [0.1, 0.2]\n"
                                             "delay_s = 0.003\ndelay_known = true\n");
  CHECK_THAT(bad, Contains("sensor[1].position_m is required"));
  CHECK_THAT(bad, Contains("sensor[1].noise_density = 0, must be > 0"));
  CHECK_THAT(bad, Contains("lqg.process_noise_density needs one entry per controller actuator (1), got 2"));
  CHECK_THAT(bad, Contains("lqg.delay_known = true needs delay_s = 0.003 to be a whole number of samples"));
}

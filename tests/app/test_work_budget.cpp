// Issue 20, item 2: every integration of a study is charged to one work budget
// (Design::study_work; a sweep's samples share Design::sweep_work). A study given exactly
// the work it needs runs as before; one unit less and it ends as a numerical failure
// (exit 1) whose message gives the time reached and the reason, and what it then left
// out. The budgets are lowered here so that spending them is cheap.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "freeflex/app/run.hpp"
#include "freeflex/io/design.hpp"
#include "support/cli.hpp"

using namespace freeflex;
using Catch::Contains;

namespace {

std::string text_of(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

Design shipped(const std::string& stem) {
  Design d = load_design(std::string(FREEFLEX_SOURCE_DIR) + "/designs/" + stem + ".toml");
  d.plots = false;
  return d;
}

RunResult run_quietly(const Design& d, const std::string& out_dir = "") {
  RunOptions o;
  o.out_dir = out_dir;
  o.sweep.threads = 1;
  return run_design(d, o);
}

}  // namespace

TEST_CASE("a [simulation] given exactly its work runs as before, one unit less fails with the time and the reason",
          "[app][issue20]") {
  Design d = shipped("paper_force_pulse");
  const RunResult full = run_quietly(d);
  REQUIRE(full.ok());
  REQUIRE(full.simulation);
  const long long used = full.simulation->work_units;
  CHECK(full.simulation->work_budget_units == design_limits::kMaxStudyWork);
  REQUIRE(used > 0);
  REQUIRE(full.simulation->perturbation->error_estimate);  // four runs: each solution and its error estimate

  d.study_work = used;
  const RunResult exact = run_quietly(d);
  REQUIRE(exact.ok());
  CHECK(exact.simulation->work_units == used);
  CHECK(exact.simulation->nonlinear->table == full.simulation->nonlinear->table);  // the budget changes no bit
  CHECK(exact.simulation->perturbation->error_estimate->q == full.simulation->perturbation->error_estimate->q);

  // the last run (the perturbation solution's error estimate) is one unit short
  d.study_work = used - 1;
  const std::string out = freeflex_test::temp_path("work_budget");  // per process: concurrent test runs do not collide
  std::filesystem::remove_all(out);
  const RunResult cut = run_quietly(d, out);
  CHECK(cut.exit_code() == kExitNumericalFailure);
  CHECK_THAT(cut.message, Contains("perturbation solution: no global error estimate: the run at rtol ") &&
                              Contains("stopped at t = ") &&
                              Contains("the [simulation] study's work budget of ") && Contains("is spent"));
  CHECK(cut.simulation->work_units <= used - 1);  // never overspent: a CVode call takes only what is left
  CHECK(cut.simulation->nonlinear->run.ok());  // what ran before stands
  const nlohmann::json summary = nlohmann::json::parse(text_of(out + "/summary.json"));
  CHECK(summary["status"] == "failed");
  CHECK_THAT(summary["message"].get<std::string>(), Contains("the [simulation] study's work budget"));
  CHECK(summary["studies"]["simulation"]["work_units"].get<long long>() <= used - 1);  // as above
  std::filesystem::remove_all(out);
}

TEST_CASE("the [controller] study's budget covers its chain and its bang-bang designs", "[app][issue20]") {
  Design d = shipped("suppress_moment_pulse");
  REQUIRE(d.bang_bang);
  const Design without = [&] {
    Design w = d;
    w.bang_bang.reset();
    return w;
  }();
  const RunResult chain_only = run_quietly(without);
  REQUIRE(chain_only.ok());
  const long long chain_work = chain_only.suppression->work_units;
  const RunResult full = run_quietly(d);
  REQUIRE(full.ok());
  // the switch-time searches' simulations and the bang-bang runs are charged too
  CHECK(full.suppression->work_units > chain_work);

  // just the chain's work: the first bang-bang design finds nothing left, the second is not run
  d.study_work = chain_work;
  const RunResult cut = run_quietly(d);
  CHECK(cut.exit_code() == kExitNumericalFailure);
  CHECK(cut.suppression->chain.ok());
  CHECK(cut.suppression->work_units == chain_work);  // nothing was left to charge
  CHECK_THAT(cut.message, Contains("bang-bang design for 1 modes did not converge") &&
                              Contains("stopped at t = 0: the [controller] study's work budget of ") &&
                              Contains("is spent: not run: the bang-bang rotation for 2 mode(s)"));
  REQUIRE(cut.suppression->bang_bang.size() == 2);
  CHECK_THAT(cut.suppression->bang_bang[1].status, Contains("not designed: the [controller] study's work budget"));

  // less than the chain's (chain_work holds it twice: its error estimate runs it again
  // at tighter tolerances): the Riccati sweep or a run before it stops, with its time
  d.study_work = chain_work / 4;
  const RunResult half = run_quietly(d);
  CHECK(half.exit_code() == kExitNumericalFailure);
  CHECK_THAT(half.message, Contains("stopped at t = ") && Contains("the [controller] study's work budget"));
  // enough for the chain, not for its error estimate: said so
  d.study_work = chain_work * 2 / 3;
  const RunResult no_estimate = run_quietly(d);
  CHECK(no_estimate.exit_code() == kExitNumericalFailure);
  CHECK_THAT(no_estimate.message, Contains("not run: the error estimate (the chain at 10x tighter tolerances, stopped)"));
}

TEST_CASE("a sweep's samples share its budget equally, each charged on its own", "[app][issue20]") {
  Design d = load_design(std::string(FREEFLEX_SOURCE_DIR) + "/tests/data/sweep_small.toml");
  REQUIRE(d.sweep);
  const long total = d.sweep->total_samples();
  const RunResult full = run_quietly(d);
  REQUIRE(full.ok());
  CHECK(full.sweep->work_share_per_sample == std::min(design_limits::kMaxStudyWork, design_limits::kMaxSweepWork / total));
  CHECK(full.sweep->sample_work_units > 0);
  CHECK(full.sweep->setup_work_units > 0);  // the digital law's discretization
  // a share below what one sample needs (its plant and 300 intervals of at least a step
  // of 400 units): every sample fails, and the run says why
  d.sweep_work = total * 10000;
  const RunResult cut = run_quietly(d);
  CHECK(cut.exit_code() == kExitNumericalFailure);
  CHECK(cut.sweep->failed == total);
  CHECK_THAT(cut.message, Contains("[sweep]: " + std::to_string(total) + " of " + std::to_string(total) +
                                   " samples failed; " + std::to_string(total) +
                                   " of them spent their share of the sweep's work budget (10000 units each"));
}

TEST_CASE("the [lqg] study's filter, digital law and flights share one budget", "[app][issue20]") {
  std::string text = text_of(std::string(FREEFLEX_SOURCE_DIR) + "/tests/data/sweep_small.toml");
  text = text.substr(0, text.find("[sweep]")) +
         "[[sensor]]\nname = \"gyro\"\ntype = \"gyro_attitude\"\nnoise_density = 1e-5\n[lqg]\nsample_rate_hz = 2000\n";
  Design d = parse_design(text, "lqg_small.toml");
  const RunResult full = run_quietly(d);
  REQUIRE(full.ok());
  REQUIRE(full.lqg);
  const long long used = full.lqg->work_units;
  CHECK(full.lqg->work_budget_units == design_limits::kMaxStudyWork);
  // the filter's discretization at 2 kHz (n³ a step of its matrix equations) outweighs the
  // [controller] study here (its chain and the chain's error estimate): a budget that
  // covers the latter stops the former
  REQUIRE(used > full.suppression->work_units);
  d.study_work = full.suppression->work_units;
  const RunResult cut = run_quietly(d);
  CHECK(cut.suppression->ok());
  CHECK(cut.exit_code() == kExitNumericalFailure);
  CHECK_THAT(cut.message, Contains("[lqg]: ") && Contains("stopped at t = ") &&
                              Contains("the [lqg] study's work budget of "));
  CHECK(cut.lqg->work_units <= d.study_work);  // never overspent
}

TEST_CASE("each suppression case estimates its energy's error, and a loose tolerance is said to be", "[app]") {
  // designs/suppress_moment_pulse.toml's chain (the bang-bang rows left out): every row of
  // the chain gets the change of its residual energy when the chain runs again at 10x
  // tighter tolerances; with closed_loop_rtol = 1e-3 the closed loops are not converged.
  Design d = shipped("suppress_moment_pulse");
  d.bang_bang.reset();
  const RunResult good = run_quietly(d);
  REQUIRE(good.ok());
  REQUIRE(good.suppression->cases.size() == 4);
  for (const auto& c : good.suppression->cases) {
    INFO(c.name << " " << c.model << ": " << c.metrics.residual_vibration_energy_J << " J, estimate "
                << c.energy_error_estimate_J);
    REQUIRE(std::isfinite(c.energy_error_estimate_J));
    CHECK(c.energy_error_estimate_J < 1e-3 * c.metrics.residual_vibration_energy_J);  // converged (measured < 1e-5)
  }
  for (const auto& w : good.warnings) CHECK_THAT(w, !Contains("not converged"));
  // switched off in the design: no estimate, half the work
  std::string text = text_of(std::string(FREEFLEX_SOURCE_DIR) + "/designs/suppress_moment_pulse.toml");
  text.replace(text.find("[controller]\n"), 13, "[controller]\nerror_estimate = false\n");
  Design off = parse_design(text, "no_estimate.toml");
  off.bang_bang.reset();
  off.plots = false;
  REQUIRE(!off.controller->error_estimate);
  const RunResult quick = run_quietly(off);
  REQUIRE(quick.ok());
  for (const auto& c : quick.suppression->cases) CHECK(std::isnan(c.energy_error_estimate_J));
  CHECK(quick.suppression->work_units < good.suppression->work_units / 2);  // the second chain is dearer

  d.controller->closed_loop_rtol = 1e-3;
  d.controller->closed_loop_atol = 1e-3;
  const RunResult loose = run_quietly(d);
  REQUIRE(loose.suppression);
  const auto& tv = loose.suppression->cases[3];
  REQUIRE(tv.name == "tvlqr");
  INFO(tv.metrics.residual_vibration_energy_J << " J, estimate " << tv.energy_error_estimate_J);
  CHECK(tv.energy_error_estimate_J > 0.1 * tv.metrics.residual_vibration_energy_J);
  bool said = false;
  for (const auto& w : loose.warnings) said = said || w.find("tvlqr (nonlinear) residual vibration energy") != std::string::npos;
  CHECK(said);
}

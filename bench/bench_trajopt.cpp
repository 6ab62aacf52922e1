// Benchmark (not a test): the two-thruster slew of tests/trajopt/test_maneuvers.cpp
// (paper beam 1 m, 1 kg, EI 1; thrusters along body y at both tips, |u| <= 1 N; rest at
// the origin to rest at (1 m, 0.5 m, 90°) in 3 s at minimum energy), solved from the
// default guess by Ipopt (tol 1e-8, exact Hessian) at N = 25 ... 800 intervals,
// trapezoidal (tr 0), Hermite–Simpson separated (tr 1) and compressed (tr 2, the
// default), the KKT systems factored by freeflex's LDLT (mumps 0, the default) or by
// MUMPS (mumps 1). Reports wall time per solve, Ipopt iterations and the time per interval
// (flat when the cost grows linearly in N).
// Goal: N = 100 Hermite–Simpson under 50 ms; cost no worse than linear in N.
//
// BM_elastic_slew: the same slew with the elastic modes inside the problem (issue 16):
// the first-order elastic state of every admissible function (elastic_modes "all"), all
// at rest at T, at NOA = 2 ... 12 and N = 50 ... 800, Hermite–Simpson separated (tr 1)
// and compressed (tr 2). Goal: NOA 6, N = 100, Hermite–Simpson under 0.3 s, time linear
// in N.
//   cmake -S . -B build-bench -DFREEFLEX_BUILD_BENCHMARKS=ON -DBUILD_TESTING=OFF
//   cmake --build build-bench --target bench_trajopt && build-bench/bench/bench_trajopt
#include <benchmark/benchmark.h>

#include <cmath>

#include "freeflex/trajopt/solve.hpp"

using namespace freeflex;

namespace {

struct Slew {
  FlexibleBody body{Beam(BeamProperties::uniform(1.0, 1.0, 1.0)), 2,
                    {{"left", ForceElement::Type::Thruster, 0.0, {0.0, 1.0}, false},
                     {"right", ForceElement::Type::Thruster, 1.0, {0.0, 1.0}, false}}};
  ManeuverProblem problem;
  Slew() {
    problem.actuators = {0, 1};
    problem.u_min = Eigen::Vector2d(-1.0, -1.0);
    problem.u_max = Eigen::Vector2d(1.0, 1.0);
    problem.x_final << 1.0, 0.5, 0.5 * std::acos(-1.0), 0.0, 0.0, 0.0;
    problem.duration_s = 3.0;
  }
};

void BM_slew(benchmark::State& state) {
  static const Slew slew;
  static const Transcription kinds[] = {Transcription::Trapezoidal, Transcription::HermiteSimpson,
                                        Transcription::HermiteSimpsonCompressed};
  TrajoptOptions o;
  o.intervals = static_cast<int>(state.range(0));
  o.transcription = kinds[state.range(1)];
  o.linear_solver = state.range(2) == 0 ? LinearSolver::Ldlt : LinearSolver::Mumps;
  TrajoptResult r;
  double total_s = 0.0;
  for (auto _ : state) {
    r = solve_maneuver(slew.body, slew.problem, o);
    total_s += r.solve_time_s;
    benchmark::DoNotOptimize(r.x.data());
  }
  if (!r.ok()) state.SkipWithError(r.message.c_str());
  const double per_solve_s = total_s / static_cast<double>(state.iterations());
  state.counters["ipopt_iter"] = r.iterations;
  state.counters["J"] = r.objective;
  state.counters["solve_ms"] = 1e3 * per_solve_s;
  state.counters["us_per_interval"] = 1e6 * per_solve_s / o.intervals;
  state.SetLabel(std::string(to_string(o.transcription)) + " " + to_string(o.linear_solver));
}

void BM_elastic_slew(benchmark::State& state) {
  const int noa = static_cast<int>(state.range(1));
  const FlexibleBody body(Beam(BeamProperties::uniform(1.0, 1.0, 1.0)), noa,
                          {{"left", ForceElement::Type::Thruster, 0.0, {0.0, 1.0}, false},
                           {"right", ForceElement::Type::Thruster, 1.0, {0.0, 1.0}, false}});
  ManeuverProblem p = Slew().problem;
  p.elastic = true;
  p.modes_at_rest = ManeuverProblem::all_modes;
  TrajoptOptions o;
  o.intervals = static_cast<int>(state.range(0));
  o.transcription = state.range(2) == 1 ? Transcription::HermiteSimpson : Transcription::HermiteSimpsonCompressed;
  o.linear_solver = state.range(3) == 0 ? LinearSolver::Ldlt : LinearSolver::Mumps;
  TrajoptResult r;
  double total_s = 0.0;
  for (auto _ : state) {
    r = solve_maneuver(body, p, o);
    total_s += r.solve_time_s;
    benchmark::DoNotOptimize(r.x.data());
  }
  if (!r.ok()) state.SkipWithError(r.message.c_str());
  const double per_solve_s = total_s / static_cast<double>(state.iterations());
  state.counters["ipopt_iter"] = r.iterations;
  state.counters["n_elastic"] = body.n();
  state.counters["solve_ms"] = 1e3 * per_solve_s;
  state.counters["us_per_interval"] = 1e6 * per_solve_s / o.intervals;
  state.SetLabel(std::string(to_string(o.transcription)) + " " + to_string(o.linear_solver));
}

}  // namespace

BENCHMARK(BM_elastic_slew)
    ->ArgsProduct({{50, 100, 200, 400, 800}, {6}, {1, 2}, {0, 1}})
    ->ArgsProduct({{100}, {2, 4, 8, 10, 12}, {1, 2}, {0, 1}})
    ->ArgNames({"N", "noa", "tr", "mumps"})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_slew)
    ->ArgsProduct({{25, 50, 100, 200, 400, 800}, {0, 1, 2}, {0, 1}})
    ->ArgNames({"N", "tr", "mumps"})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();

// Benchmark (not a test): TV-LQR solve time (backward Riccati, feedforward and gains on
// the 5 ms grid) for the paper's moment example (M_z = ±1 N m pulse at the centre of the
// 1 m, 1 kg, EI = 1 beam; feedback by a torque at o and body-y thrusters at both tips),
// horizon 3 s, Q = vibration_weight(1, 10, 1), R = diag(1, 1/4, 1/4), rtol 1e-8 (and
// 1e-6), for NOA = 6, 20 and 40, by each method (0 auto, 1 BDF, 2 exponential).
// Issue 19 item 3: under 200 ms at NOA = 20, NOA = 6 under 20 ms (docs/benchmarks.md).
//   cmake -S . -B build-bench -DFREEFLEX_BUILD_BENCHMARKS=ON && cmake --build build-bench
//   build-bench/bench/bench_control
#include <benchmark/benchmark.h>

#include <memory>
#include <string>

#include "freeflex/control/closed_loop.hpp"
#include "freeflex/control/tvlqr.hpp"
#include "freeflex/sim/simulate.hpp"
#include "tvlqr_case.hpp"

using namespace freeflex;

namespace {


void BM_tvlqr(benchmark::State& state) {
  const double rtol = state.range(1) == 0 ? 1e-8 : 1e-6;
  const auto c = freeflex_bench::moment_case(static_cast<int>(state.range(0)));
  TvlqrOptions options;
  options.rtol = rtol;
  const TvlqrOptions::Method methods[] = {TvlqrOptions::Method::Auto, TvlqrOptions::Method::Bdf,
                                          TvlqrOptions::Method::Exponential};
  options.method = methods[state.range(2)];
  TvlqrResult r;
  for (auto _ : state) {
    r = solve_tvlqr(*c->model, 0.0, 3.0, c->Q, c->R, options);
    benchmark::DoNotOptimize(r.K.data());
  }
  if (!r.ok()) state.SkipWithError(r.message.c_str());
  state.counters["steps"] = static_cast<double>(r.steps);
  state.counters["rhs_evals"] = static_cast<double>(r.rhs_evaluations);
  state.counters["gmres_iters"] = static_cast<double>(r.linear_iterations);
  state.counters["prec_setups"] = static_cast<double>(r.preconditioner_setups);
  state.SetLabel(std::string(state.range(1) == 0 ? "rtol 1e-8, " : "rtol 1e-6, ") + to_string(r.method));
}

}  // namespace

// NOA 40 by BDF takes about 10 s a solve: left out
BENCHMARK(BM_tvlqr)
    ->ArgsProduct({{6, 20}, {0, 1}, {0, 1, 2}})
    ->Args({40, 0, 0})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();

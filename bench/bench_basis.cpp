// Benchmark (not a test), issue 15: the two shape bases against the number of functions n.
//  * BM_build: the discretized body (basis, modal integrals, force-element values) of
//    the stepped beam with hub and tip mass (tests/reference/README.md section A), on the
//    paper's basis with NOA = n and on the finite-element basis keeping n modes of 40 and
//    of 100 quintic elements.
//  * BM_full: the paper's moment example (M_z = +-1 N m at the centre of the uniform 1 m,
//    1 kg, EI = 1 beam, 0-1 s) to 3 s with the full nonlinear model (Adams, physical
//    variables, rtol 1e-8, atol 1e-10: bench_simulation's case) on either basis.
//   cmake -S . -B build-bench -DFREEFLEX_BUILD_BENCHMARKS=ON && cmake --build build-bench
//   build-bench/bench/bench_basis
#include <benchmark/benchmark.h>

#include <string>

#include "freeflex/sim/simulate.hpp"
#include "support/reference_csv.hpp"  // the tests' stepped beam

using namespace freeflex;

namespace {

/// range(0) = n; range(1): 0 paper, otherwise that many quintic elements.
BasisOptions basis_of(const benchmark::State& state) {
  BasisOptions b;
  if (state.range(1) > 0) {
    b.kind = BasisOptions::Kind::FiniteElement;
    b.finite_element = {static_cast<int>(state.range(1)), 5};
  }
  return b;
}

std::string label(const benchmark::State& state) {
  return state.range(1) == 0 ? "paper" : "finite_element, " + std::to_string(state.range(1)) + " quintic";
}

void BM_build(benchmark::State& state) {
  const Beam beam(freeflex_test::stepped_beam(true));
  const std::vector<ForceElement> elements{{"left", ForceElement::Type::Thruster, 0.0, {0.0, 1.0}, false},
                                           {"right", ForceElement::Type::Thruster, 1.0, {0.0, 1.0}, false}};
  const BasisOptions basis = basis_of(state);
  for (auto _ : state) {
    const FlexibleBody body(beam, static_cast<int>(state.range(0)), basis, elements);
    benchmark::DoNotOptimize(body.integrals().K.data());
  }
  state.SetLabel(label(state));
}

void BM_full(benchmark::State& state) {
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  const FlexibleBody body(beam, static_cast<int>(state.range(0)), basis_of(state),
                          {{"Mz", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false}});
  const Excitation ex{{TimeProfile(TimeProfile::Kind::Steps, {0.0, 0.5, 1.0}, {1.0, -1.0})}};
  SimulationOptions opt;
  opt.duration_s = 3.0;
  opt.output_step_s = 0.01;
  opt.integrator.rtol = 1e-8;
  opt.integrator.atol = 1e-10;
  opt.integrator.method = IntegratorOptions::Method::Adams;
  opt.full_variables = SimulationOptions::Variables::Physical;
  SimulationResult r;
  for (auto _ : state) {
    r = simulate_full(body, ex, opt);
    benchmark::DoNotOptimize(r.z.data());
  }
  if (!r.ok()) state.SkipWithError(r.message.c_str());
  state.counters["rhs_evals"] = static_cast<double>(r.rhs_evaluations);
  state.counters["steps"] = static_cast<double>(r.steps);
  state.SetLabel(label(state));
}

}  // namespace

BENCHMARK(BM_build)->ArgsProduct({{6, 12, 20, 40}, {0, 40, 100}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_full)->ArgsProduct({{6, 12, 20}, {0, 40}})->Unit(benchmark::kMillisecond)->Iterations(3);

BENCHMARK_MAIN();

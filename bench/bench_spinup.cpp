// Benchmark (not a test; issue 14, acceptance 7): the cost of geometric stiffening.
//  * BM_spinup: the Kane-Ryan-Banerjee spin-up (designs/spinup_krb.toml: 10 m cantilever
//    clamped to a hub spun up to 4 rad/s over 15 s) to 20 s with stiffening, NOA 6, rtol
//    1e-8, atol 1e-10: the full model and the first-order model under the prescribed motion.
//  * BM_free: a free body (the paper's beam, NOA 6) under the paper's force and moment
//    pulses to 3 s, full model, with and without stiffening: what the rank-four mass
//    update and the extra terms cost per right-hand side and per run; and with and
//    without the work quadrature of the energy balance (SimulationOptions::energy_balance).
// Reports wall time per simulation and the right-hand-side evaluation count.
//   cmake -S . -B build-bench -DFREEFLEX_BUILD_BENCHMARKS=ON && cmake --build build-bench
//   build-bench/bench/bench_spinup
#include <benchmark/benchmark.h>

#include "freeflex/sim/prescribed.hpp"
#include "freeflex/sim/simulate.hpp"

using namespace freeflex;

namespace {

FlexibleBody krb_body(bool stiffening) {
  BeamProperties p;
  p.segments = {{10.0, 1.2, 14000.0}};
  p.reference_m = 0.0;
  return FlexibleBody(Beam(p), 6, {}, {}, stiffening);
}

SimulationOptions options(double duration) {
  SimulationOptions o;
  o.duration_s = duration;
  o.output_step_s = 0.01;
  o.integrator.rtol = 1e-8;
  o.integrator.atol = 1e-10;
  o.energy_balance = true;  // as freeflex run does (BM_free switches it)
  return o;
}

void BM_spinup(benchmark::State& state) {
  const bool first_order = state.range(0) == 1;
  const FlexibleBody body = krb_body(true);
  const PrescribedMotion motion({}, {}, MotionProfile::spin_up(4.0, 15.0));
  const SimulationOptions o = options(20.0);
  SimulationResult r;
  for (auto _ : state) {
    r = simulate_prescribed(body, Excitation{}, motion, o, first_order);
    benchmark::DoNotOptimize(r.z.data());
  }
  if (!r.ok()) state.SkipWithError(r.message.c_str());
  state.counters["rhs_evals"] = static_cast<double>(r.rhs_evaluations);
  state.counters["steps"] = static_cast<double>(r.steps);
  state.SetLabel(first_order ? "first order, stiffened" : "full, stiffened");
}
BENCHMARK(BM_spinup)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_free(benchmark::State& state) {
  const bool moment = state.range(0) == 1, stiffening = state.range(1) == 1, balance = state.range(2) == 1;
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  const ForceElement e = moment ? ForceElement{"Mz", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false}
                                : ForceElement{"Fy", ForceElement::Type::Force, 0.5, {0.0, 1.0}, false};
  const FlexibleBody body(beam, 6, {e}, {}, stiffening);
  const Excitation ex{{TimeProfile(TimeProfile::Kind::Steps, {0.0, 0.5, 1.0}, {1.0, -1.0})}};
  SimulationOptions o = options(3.0);
  o.energy_balance = balance;
  SimulationResult r;
  for (auto _ : state) {
    r = simulate_full(body, ex, o);
    benchmark::DoNotOptimize(r.z.data());
  }
  state.counters["rhs_evals"] = static_cast<double>(r.rhs_evaluations);
  state.counters["steps"] = static_cast<double>(r.steps);
  state.counters["t_reached"] = r.t.size() ? r.t(r.t.size() - 1) : 0.0;
  state.SetLabel(std::string(moment ? "moment pulse" : "force pulse") + (stiffening ? ", stiffened" : ", paper model") +
                 (balance ? ", energy balance" : "") +
                 (r.ok() ? "" : " (" + std::string(to_string(r.status)) + ")"));
}
BENCHMARK(BM_free)
    ->Args({0, 0, 1})
    ->Args({0, 1, 1})
    ->Args({1, 0, 1})
    ->Args({1, 1, 1})
    ->Args({0, 0, 0})
    ->Args({1, 0, 0})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

// Benchmark (not a test): the paper's moment example (M_z = +-1 N m pulse at the
// centre of the 1 m, 1 kg, EI = 1 beam) to 3 s at rtol 1e-8, atol 1e-10, for NOA = 6
// and 20, with the full nonlinear model and the perturbation solution, Adams in modal
// and in physical variables (docs/theory.md section 8), and BDF in physical variables.
// Reports wall time per simulation and the right-hand-side evaluation count, and an
// estimate of the floor CVODES sets: its Adams steps on the free oscillation alone.
// DOP853 and Verner 9(8) (freeflex's explicit Runge-Kutta pairs) in both variables too. FREEFLEX_RTOL=x
// sets rtol = x, atol = x/100 (as bench_accuracy) for every case.
// Goal (issue 3): under 20 ms for NOA = 6.
//   cmake -S . -B build-bench -DFREEFLEX_BUILD_BENCHMARKS=ON && cmake --build build-bench
//   build-bench/bench/bench_simulation
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <string>

#include "freeflex/sim/integrator.hpp"
#include "sim/modal_variables.hpp"  // private to src/: the benchmark reads the modes it integrates
#include "freeflex/sim/simulate.hpp"

using namespace freeflex;

namespace {

struct Case {
  FlexibleBody body;
  Excitation ex;
  SimulationOptions opt;
};

Case moment_case(int noa, IntegratorOptions::Method method, bool modal) {
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  Case c{FlexibleBody(beam, noa, {{"Mz", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false}}),
         Excitation{{TimeProfile(TimeProfile::Kind::Steps, {0.0, 0.5, 1.0}, {1.0, -1.0})}}, SimulationOptions{}};
  c.opt.duration_s = 3.0;
  c.opt.output_step_s = 0.01;
  c.opt.integrator.rtol = 1e-8;
  c.opt.integrator.atol = 1e-10;
  c.opt.integrator.method = method;
  const auto v = modal ? SimulationOptions::Variables::Modal : SimulationOptions::Variables::Physical;
  c.opt.full_variables = c.opt.first_order_variables = v;
  if (const char* mo = std::getenv("FREEFLEX_MAX_ORDER")) c.opt.integrator.max_order = std::atoi(mo);
  if (const char* rt = std::getenv("FREEFLEX_RTOL")) {  // atol = rtol / 100, as bench_accuracy
    c.opt.integrator.rtol = std::atof(rt);
    c.opt.integrator.atol = c.opt.integrator.rtol * 1e-2;
  }
  return c;
}

std::string label(const benchmark::State& state) {
  static const char* const names[] = {"bdf", "adams", "dop853", "verner98"};
  return std::string(names[state.range(1)]) +
         (state.range(2) == 1 ? " modal" : " physical");
}

IntegratorOptions::Method method_of(int64_t m) {
  using M = IntegratorOptions::Method;
  return m == 0 ? M::Bdf : m == 1 ? M::Adams : m == 2 ? M::Dop853 : M::Verner98;
}

void BM_full(benchmark::State& state) {
  const Case c = moment_case(static_cast<int>(state.range(0)), method_of(state.range(1)), state.range(2) == 1);
  SimulationResult r;
  for (auto _ : state) {
    r = simulate_full(c.body, c.ex, c.opt);
    benchmark::DoNotOptimize(r.z.data());
  }
  if (!r.ok()) state.SkipWithError(r.message.c_str());
  state.counters["rhs_evals"] = static_cast<double>(r.rhs_evaluations);
  state.counters["steps"] = static_cast<double>(r.steps);
  state.SetLabel(label(state));
}

void BM_perturbation(benchmark::State& state) {
  const Case c = moment_case(static_cast<int>(state.range(0)), method_of(state.range(1)), state.range(2) == 1);
  PerturbationResult r;
  for (auto _ : state) {
    r = simulate_perturbation(c.body, c.ex, c.opt);
    benchmark::DoNotOptimize(r.total.z.data());
  }
  if (!r.total.ok()) state.SkipWithError(r.total.message.c_str());
  state.counters["rhs_evals"] = static_cast<double>(r.total.rhs_evaluations);
  state.counters["zero_order_rhs"] = static_cast<double>(r.zero_order.rhs_evaluations);
  state.counters["first_order_rhs"] = static_cast<double>(r.first_order_rhs_evaluations);
  state.SetLabel(label(state));
}

// An estimate of the floor CVODES sets on this case: the same integrator settings, pieces
// and output times on the NOA-N model linearized at rest with its modes uncoupled
// (x = [r, η], r'' = 0, η_k'' = -ω_k² η_k), so that the right-hand side costs almost
// nothing. It starts from the free oscillation the pulse leaves (the full model's state at
// 1 s, in modal coordinates), so its steps are what fixed-point Adams needs to follow that
// oscillation alone, without the coupling. Only NOA 6 is run.
void BM_cvode_floor(benchmark::State& state) {
  const Case c = moment_case(static_cast<int>(state.range(0)), IntegratorOptions::Method::Adams, false);
  const ModalVariables modes(
      c.body, [](const Instant&, const Eigen::Ref<const Eigen::VectorXd>&, Eigen::Ref<Eigen::VectorXd>) { return false; });
  const Eigen::VectorXd w2 = modes.natural_frequencies().cwiseAbs2();
  const int n = static_cast<int>(w2.size()), N = n + 3;
  OdeSystem sys;
  sys.dim = 2 * N;
  sys.rhs = [&](const Instant&, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> xd) {
    xd.head(N) = x.tail(N);
    xd.segment(N, 3).setZero();
    xd.tail(n) = -w2.cwiseProduct(x.segment(3, n));
    return true;
  };
  SimulationOptions to_1s = c.opt;
  to_1s.duration_s = 1.0;
  const SimulationResult pulse = simulate_full(c.body, c.ex, to_1s);
  if (!pulse.ok()) {
    state.SkipWithError(pulse.message.c_str());
    return;
  }
  const Eigen::Index last = pulse.t.size() - 1;
  const auto phi = modes.mode_shapes().partialPivLu();
  Eigen::VectorXd x0(2 * N);
  x0.head(3) = pulse.z.row(last).head(3).transpose();
  x0.segment(3, n) = phi.solve(pulse.z.row(last).tail(n).transpose());
  x0.segment(N, 3) = pulse.z_dot.row(last).head(3).transpose();
  x0.tail(n) = phi.solve(pulse.z_dot.row(last).tail(n).transpose());
  std::vector<double> times;
  for (int k = 0; k <= 300; ++k) times.push_back(0.01 * k);
  IntegrationResult r;
  for (auto _ : state) {
    r = integrate(sys, x0, times, {0.5, 1.0}, c.opt.integrator);
    benchmark::DoNotOptimize(r.x.data());
  }
  if (!r.ok()) state.SkipWithError(r.message.c_str());
  state.counters["rhs_evals"] = static_cast<double>(r.rhs_evaluations);
  state.counters["steps"] = static_cast<double>(r.steps);
  state.counters["omega_max"] = modes.natural_frequencies().maxCoeff();
  state.SetLabel("adams, uncoupled oscillators");
}

}  // namespace

// Arguments: NOA, method (0 BDF, 1 Adams, 2 DOP853, 3 Verner 9(8)), variables (0 physical, 1 modal).
#define FREEFLEX_SIM_CASES                                                                              \
  ArgsProduct({{6, 20}, {1}, {1, 0}})->Args({6, 0, 0})->Args({20, 0, 0})->Args({6, 2, 0})->Args({20, 2, 0}) \
      ->Args({6, 2, 1})->Args({20, 2, 1})->Args({6, 3, 0})->Args({20, 3, 0})->Args({6, 3, 1})->Args({20, 3, 1}) \
      ->Unit(benchmark::kMillisecond)
BENCHMARK(BM_full)->FREEFLEX_SIM_CASES;
BENCHMARK(BM_perturbation)->FREEFLEX_SIM_CASES;
BENCHMARK(BM_cvode_floor)->Arg(6)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();

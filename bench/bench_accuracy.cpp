// Benchmark (not a test): work and precision of the simulations, issue 19 acceptance 2.
// The paper's moment example (M_z = +-1 N m pulse at the centre of the 1 m, 1 kg, EI = 1
// beam, 0-1 s), NOA 6 over 0-3 s and NOA 20 over 0-1 s, output every 10 ms. For each
// integration option and rtol 1e-6 ... 1e-12 (atol = rtol / 100): the error in θ and q
// against a tight reference of the same model (max over the output times), the global
// error estimate freeflex reports (a second run at rtol/10, GlobalErrorEstimate), their
// ratio, CPU time (minimum of `reps` runs) and steps. Prints a Markdown table.
//
//   build/bench/bench_accuracy [reps] [--only TEXT] [--noa N]...   the table (rows whose
//       name contains TEXT; NOA 6 over 3 s, 20 and 40 over 1 s; default 3 reps, NOA 6 and 20)
//   build/bench/bench_accuracy 3 --sweep 1e-4 [--noa N]...   work at an error of 1e-4 rad:
//       many tolerances, a fit of error against RHS (full model; Adams, DOP853, Verner);
//       with --rtol x (repeatable) at those tolerances only; --atol-ratio R: atol = R rtol
//       in the measured runs (default 0.01; the references keep it)
//   build/bench/bench_accuracy 3 --perturbation 1e-8 --noa 20   the perturbation solution's
//       work by time span and method
//   build/bench/bench_accuracy --export DIR      model data, right-hand sides at random
//       states and the reference θ(t), q(t) for scripts/dop853_compare.py (SciPy rows)
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "freeflex/dynamics/full_model.hpp"
#include "freeflex/sim/simulate.hpp"
#include "tvlqr_case.hpp"

using namespace freeflex;

namespace {

using freeflex_bench::cpu_seconds;

struct Case {
  FlexibleBody body;
  Excitation ex;
};

Case moment_case(int noa) {
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  return {FlexibleBody(beam, noa, {{"Mz", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false}}),
          Excitation{{TimeProfile(TimeProfile::Kind::Steps, {0.0, 0.5, 1.0}, {1.0, -1.0})}}};
}

double g_atol_ratio = 1e-2;  ///< atol = rtol times this in the measured runs (--atol-ratio); references keep 1e-2

SimulationOptions options(double duration, double rtol, IntegratorOptions::Method m, SimulationOptions::Variables v,
                          double atol_ratio = 1e-2) {
  SimulationOptions o;
  o.duration_s = duration;
  o.output_step_s = 0.01;
  o.integrator.rtol = rtol;
  o.integrator.atol = rtol * atol_ratio;
  o.integrator.method = m;
  o.full_variables = v;
  if (v != SimulationOptions::Variables::RestModes) o.first_order_variables = v;  // the full model's only
  return o;
}

struct Option {
  const char* name;
  bool full;
  IntegratorOptions::Method method;
  SimulationOptions::Variables variables;
  std::vector<double> rtols;  ///< empty: 1e-6, 1e-8, 1e-10, 1e-12
  bool taylor = false;        ///< the perturbation solution by Taylor series
};

double load_average() {
  double l = -1.0;
  std::ifstream f("/proc/loadavg");
  f >> l;
  return l;
}

SimulationResult run(const Case& c, const Option& op, const SimulationOptions& o) {
  return op.full ? simulate_full(c.body, c.ex, o) : simulate_perturbation(c.body, c.ex, o).total;
}

void table(int reps, const std::string& only, const std::vector<int>& noas) {
  using M = IntegratorOptions::Method;
  using V = SimulationOptions::Variables;
  const std::vector<double> tight{1e-6, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12};
  const Option opts[] = {{"full, Adams, physical (default)", true, M::Adams, V::Physical, {}},
                         {"full, Adams, modal", true, M::Adams, V::Modal, {}},
                         {"full, BDF, physical", true, M::Bdf, V::Physical, {}},
                         {"full, DOP853, physical", true, M::Dop853, V::Physical, tight},
                         {"full, Verner 9(8), physical", true, M::Verner98, V::Physical, tight},
                         {"full, DOP853, rest modes", true, M::Dop853, V::RestModes, tight},
                         {"full, Verner 9(8), rest modes", true, M::Verner98, V::RestModes, tight},
                         {"perturbation, Adams, modal (default)", false, M::Adams, V::Modal, {}},
                         {"perturbation, Adams, physical", false, M::Adams, V::Physical, {}},
                         {"perturbation, DOP853, modal", false, M::Dop853, V::Modal, {1e-6, 1e-8, 1e-10}},
                         {"perturbation, DOP853, physical", false, M::Dop853, V::Physical, {1e-6, 1e-8, 1e-10}},
                         {"perturbation, Taylor", false, M::Adams, V::Modal, {}, true}};
  std::cout << "load average at start: " << load_average() << "\n\n";
  std::cout << "| NOA | model, method, variables | rtol | error θ [rad] | estimate θ | ratio | error q | estimate q "
               "| ratio | CPU [ms] | steps | RHS |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- "
               "|\n";
  for (int noa : noas) {
    const double T = noa == 20 || noa == 40 ? 1.0 : 3.0;
    const Case c = moment_case(noa);
    // References: each model at rtol 1e-13 with Adams, the full model in physical variables,
    // the perturbation solution in modal ones (in physical variables its error at 1e-12 is
    // 7.5e-10 rad at NOA 6, against 1.7e-10 in modal ones, so it is the poorer reference).
    const SimulationOptions ref_o = options(T, 1e-13, M::Adams, V::Physical);
    const SimulationResult ref_full = simulate_full(c.body, c.ex, ref_o);
    const SimulationResult ref_pert =
        simulate_perturbation(c.body, c.ex, options(T, 1e-13, M::Adams, V::Modal)).total;
    // The references' own error: against rtol 1e-14 (printed for the record).
    const SimulationOptions ref2_o = options(T, 1e-14, M::Adams, V::Physical);
    const SimulationResult ref2_full = simulate_full(c.body, c.ex, ref2_o);
    std::cerr << "NOA " << noa << ": full reference rtol 1e-13 vs 1e-14: theta "
              << (ref_full.z.col(2) - ref2_full.z.col(2)).cwiseAbs().maxCoeff() << ", q "
              << (ref_full.z.rightCols(noa) - ref2_full.z.rightCols(noa)).cwiseAbs().maxCoeff() << '\n';
    for (const Option& op : opts) {
      if (!only.empty() && std::string(op.name).find(only) == std::string::npos) continue;
      if (noa >= 20 && !op.full && op.variables == V::Physical) continue;  // 0.35 s a run; not needed
      const std::vector<double> rtols = op.rtols.empty() ? std::vector<double>{1e-6, 1e-8, 1e-10, 1e-12} : op.rtols;
      for (double rtol : rtols) {
        if (op.method == M::Bdf && rtol < 1e-10) continue;  // BDF at 1e-12: minutes
        SimulationOptions o = options(T, rtol, op.method, op.variables, g_atol_ratio);
        if (op.taylor) o.first_order_solver = SimulationOptions::FirstOrderSolver::Taylor;
        SimulationResult r;
        double best = 1e300;
        for (int k = 0; k < reps; ++k) {
          const double t0 = cpu_seconds();
          r = run(c, op, o);
          best = std::min(best, cpu_seconds() - t0);
        }
        const SimulationOptions o2 = error_reference_options(o);
        const GlobalErrorEstimate e = compare_runs(r, run(c, op, o2), o2);
        const SimulationResult& ref = op.full ? ref_full : ref_pert;
        if (!r.ok() || !e.available) {
          std::cout << "| " << noa << " | " << op.name << " | " << rtol << " | failed: " << r.message << e.message
                    << " |\n";
          continue;
        }
        const double et = (r.z.col(2) - ref.z.col(2)).cwiseAbs().maxCoeff();
        const double eq = (r.z.rightCols(noa) - ref.z.rightCols(noa)).cwiseAbs().maxCoeff();
        std::cout << std::setprecision(2) << "| " << noa << " | " << op.name << " | " << rtol << " | " << et << " | "
                  << e.theta_rad << " | " << e.theta_rad / et << " | " << eq << " | " << e.q << " | " << e.q / eq
                  << " | " << std::setprecision(3) << 1e3 * best << " | " << r.steps << " | " << r.rhs_evaluations
                  << " |" << std::endl;
      }
    }
  }
}

/// Work at equal error: the full model at many tolerances (10^(-k/4)), each row's θ error
/// against the reference, RHS and CPU time; then a least-squares line of log error against
/// log work through the rows with errors within a factor of 10 of `target` rad (the motion
/// is sensitive, so single rows scatter by factors of 2-4), read at `target`; the CPU time
/// there is that many RHS at the median CPU time per RHS of those rows (single CPU times
/// on the shared machine scatter more than the RHS counts).
void sweep(int reps, const std::string& only, const std::vector<int>& noas, double target,
           const std::vector<double>& chosen) {
  using M = IntegratorOptions::Method;
  using V = SimulationOptions::Variables;
  const Option opts[] = {{"full, Adams, physical (default)", true, M::Adams, V::Physical, {}},
                         {"full, DOP853, physical", true, M::Dop853, V::Physical, {}},
                         {"full, Verner 9(8), physical", true, M::Verner98, V::Physical, {}},
                         {"full, DOP853, rest modes", true, M::Dop853, V::RestModes, {}},
                         {"full, Verner 9(8), rest modes", true, M::Verner98, V::RestModes, {}}};
  std::cout << "load average at start: " << load_average() << "\n";
  for (int noa : noas) {
    const double T = noa == 20 || noa == 40 ? 1.0 : 3.0;
    const Case c = moment_case(noa);
    const SimulationResult ref = simulate_full(c.body, c.ex, options(T, 1e-13, M::Adams, V::Physical));
    for (const Option& op : opts) {
      if (!only.empty() && std::string(op.name).find(only) == std::string::npos) continue;
      std::cout << "\nNOA " << noa << ", " << op.name << ", 0-" << T << " s\n\n| rtol | error θ [rad] | RHS | steps | CPU [ms] |\n"
                << "| --- | --- | --- | --- | --- |\n";
      double sx = 0, sy = 0, sxx = 0, sxy = 0;
      std::vector<double> per_rhs;
      int m = 0;
      // rtol 10^(-k/8): NOA 6 needs 1e-9 to 1e-12 for errors near 1e-4 (the motion to 3 s is
      // sensitive), NOA 20 over 1 s 1e-5 to 1e-9
      const bool adams = op.method == M::Adams;
      const int k_first = noa == 6 ? (adams ? 80 : 64) : (adams ? 40 : 32), k_last = noa == 6 ? (adams ? 100 : 92) : 72;
      std::vector<double> rtols = chosen;
      if (rtols.empty())
        for (int k = k_first; k <= k_last; k += 2) rtols.push_back(std::pow(10.0, -k / 8.0));
      for (double rtol : rtols) {
        SimulationOptions o = options(T, rtol, op.method, op.variables, g_atol_ratio);
        if (op.taylor) o.first_order_solver = SimulationOptions::FirstOrderSolver::Taylor;
        SimulationResult r;
        double best = 1e300;
        for (int i = 0; i < reps; ++i) {
          const double t0 = cpu_seconds();
          r = run(c, op, o);
          best = std::min(best, cpu_seconds() - t0);
        }
        if (!r.ok()) {
          std::cout << "| " << rtol << " | failed: " << r.message << " |\n";
          continue;
        }
        const double et = (r.z.col(2) - ref.z.col(2)).cwiseAbs().maxCoeff();
        std::cout << std::setprecision(3) << "| " << rtol << " | " << std::setprecision(2) << et << " | "
                  << r.rhs_evaluations << " | " << r.steps << " | " << std::setprecision(3) << 1e3 * best << " |"
                  << std::endl;
        if (et < 0.1 * target || et > 10.0 * target) continue;
        const double x = std::log(static_cast<double>(r.rhs_evaluations)), y = std::log(et);
        sx += x, sy += y, sxx += x * x, sxy += x * y;
        per_rhs.push_back(best / r.rhs_evaluations);
        ++m;
      }
      if (m < 3) continue;
      const double b = (m * sxy - sx * sy) / (m * sxx - sx * sx), a = (sy - b * sx) / m;
      std::sort(per_rhs.begin(), per_rhs.end());
      const double rhs_at = std::exp((std::log(target) - a) / b), cpu_per_rhs = per_rhs[per_rhs.size() / 2];
      std::cout << "\nfit over " << m << " rows: error ~ RHS^" << std::setprecision(3) << b << "; at error " << target
                << " rad: " << std::setprecision(4) << rhs_at << " RHS, " << 1e3 * rhs_at * cpu_per_rhs
                << " ms CPU (" << 1e9 * cpu_per_rhs << " ns a RHS)\n";
    }
  }
}

/// The perturbation solution's work by time span (issue 19: NOA 20 under 20 ms at rtol
/// 1e-8 over 3 s): for each method and variables, RHS, steps and CPU time of runs to 0.5,
/// 1, 2 and 3 s (the differences are the spans' shares) and the error of the 3 s run
/// against the same solution at rtol 1e-13 (Adams, modal).
void perturbation_spans(int reps, const std::vector<int>& noas, double rtol) {
  using M = IntegratorOptions::Method;
  using V = SimulationOptions::Variables;
  const Option opts[] = {{"Adams, modal (default)", false, M::Adams, V::Modal, {}},
                         {"DOP853, modal", false, M::Dop853, V::Modal, {}},
                         {"Verner 9(8), modal", false, M::Verner98, V::Modal, {}},
                         {"Adams, physical", false, M::Adams, V::Physical, {}},
                         {"Taylor", false, M::Adams, V::Modal, {}, true}};
  std::cout << "load average at start: " << load_average() << "\n\nrtol " << rtol << ", atol rtol/100\n\n";
  std::cout << "| NOA | method, variables | to [s] | RHS | steps | CPU [ms] | error θ at 3 s [rad] | error q |\n"
            << "| --- | --- | --- | --- | --- | --- | --- | --- |\n";
  for (int noa : noas) {
    const Case c = moment_case(noa);
    const SimulationResult ref = simulate_perturbation(c.body, c.ex, options(3.0, 1e-13, M::Adams, V::Modal)).total;
    for (const Option& op : opts) {
      for (double T : {0.5, 1.0, 2.0, 3.0}) {
        SimulationOptions o = options(T, rtol, op.method, op.variables, g_atol_ratio);
        if (op.taylor) o.first_order_solver = SimulationOptions::FirstOrderSolver::Taylor;
        SimulationResult r;
        double best = 1e300;
        for (int i = 0; i < reps; ++i) {
          const double t0 = cpu_seconds();
          r = simulate_perturbation(c.body, c.ex, o).total;
          best = std::min(best, cpu_seconds() - t0);
        }
        std::cout << std::setprecision(3) << "| " << noa << " | " << op.name << " | " << T << " | "
                  << r.rhs_evaluations << " | " << r.steps << " | " << 1e3 * best << " | ";
        if (T == 3.0 && r.ok())
          std::cout << std::setprecision(2) << (r.z.col(2) - ref.z.col(2)).cwiseAbs().maxCoeff() << " | "
                    << (r.z.rightCols(noa) - ref.z.rightCols(noa)).cwiseAbs().maxCoeff() << " |\n";
        else
          std::cout << (r.ok() ? "" : r.message) << " | |\n";
      }
    }
  }
}

/// Model data (JSON), right-hand sides at random states (CSV) and the reference run of the
/// full model (CSV) for the SciPy comparison.
void export_case(const std::string& dir) {
  for (int noa : {6, 20, 40}) {
    const double T = noa == 6 ? 3.0 : 1.0;
    const Case c = moment_case(noa);
    const ModalIntegrals& mi = c.body.integrals();
    const int n = noa, N = n + 3;
    std::ofstream js(dir + "/model_noa" + std::to_string(noa) + ".json");
    js << std::setprecision(17);
    auto vec = [&](const Eigen::Ref<const Eigen::RowVectorXd>& v) {
      js << '[';
      for (int i = 0; i < v.size(); ++i) js << (i ? ", " : "") << v(i);
      js << ']';
    };
    auto mat = [&](const Eigen::MatrixXd& A) {
      js << '[';
      for (int i = 0; i < A.rows(); ++i) {
        js << (i ? ", " : "");
        vec(A.row(i));
      }
      js << ']';
    };
    js << "{\"noa\": " << n << ", \"m\": " << mi.m << ", \"S_o\": " << mi.S_o << ", \"I_o\": " << mi.I_o
       << ", \"duration_s\": " << T << ", \"torque_at_m\": 0.5,\n \"Phi_bar\": ";
    vec(mi.Phi_bar);
    js << ",\n \"Phi_tilde\": ";
    vec(mi.Phi_tilde);
    js << ",\n \"M\": ";
    mat(mi.M);
    js << ",\n \"K\": ";
    mat(mi.K);
    js << ",\n \"torque_slope\": ";
    vec(c.body.element_slope(0));
    js << "}\n";
    // Right-hand sides at random states of moderate size, the command +1 and -1.
    const FullModel model(c.body);
    FullModel::Data d = model.create_data();
    std::mt19937 gen(19);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    std::ofstream rc(dir + "/rhs_noa" + std::to_string(noa) + ".csv");
    rc << std::setprecision(17);
    for (int k = 0; k < 20; ++k) {
      Eigen::VectorXd x(2 * N);
      for (int i = 0; i < 2 * N; ++i) x(i) = U(gen) * (i < N ? (i >= 3 ? 0.05 : 3.0) : (i >= N + 3 ? 2.0 : 20.0));
      const Eigen::VectorXd u = Eigen::VectorXd::Constant(1, k % 2 ? -1.0 : 1.0);
      if (!model.rhs(d, x, u)) continue;
      rc << u(0);
      for (int i = 0; i < 2 * N; ++i) rc << ',' << x(i);
      for (int i = 0; i < 2 * N; ++i) rc << ',' << d.x_dot(i);
      rc << '\n';
    }
    const SimulationResult ref =
        simulate_full(c.body, c.ex, options(T, 1e-13, IntegratorOptions::Method::Adams, SimulationOptions::Variables::Physical));
    std::ofstream rf(dir + "/reference_noa" + std::to_string(noa) + ".csv");
    rf << std::setprecision(17);
    for (int i = 0; i < ref.t.size(); ++i) {
      rf << ref.t(i);
      for (int j = 0; j < N; ++j) rf << ',' << ref.z(i, j);
      rf << '\n';
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--export") {
    export_case(argv[2]);
    return 0;
  }
  // [reps] [--only SUBSTRING] [--noa N ...] [--sweep TARGET]
  int reps = 3;
  std::string only;
  std::vector<int> noas;
  double target = 0.0, pert_rtol = 0.0;
  std::vector<double> chosen;  // --rtol x (repeatable): the sweep at these tolerances only
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--rtol" && i + 1 < argc)
      chosen.push_back(std::atof(argv[++i]));
    else if (a == "--atol-ratio" && i + 1 < argc)
      g_atol_ratio = std::atof(argv[++i]);
    else if (a == "--perturbation" && i + 1 < argc)
      pert_rtol = std::atof(argv[++i]);
    else if (a == "--sweep" && i + 1 < argc)
      target = std::atof(argv[++i]);
    else if (a == "--only" && i + 1 < argc)
      only = argv[++i];
    else if (a == "--noa" && i + 1 < argc)
      noas.push_back(std::atoi(argv[++i]));
    else
      reps = std::atoi(argv[i]);
  }
  if (noas.empty()) noas = {6, 20};
  if (pert_rtol > 0.0)
    perturbation_spans(reps, noas, pert_rtol);
  else if (target > 0.0)
    sweep(reps, only, noas, target, chosen);
  else
    table(reps, only, noas);
  std::cout << "\nload average at end: " << load_average() << "\n";
  return 0;
}

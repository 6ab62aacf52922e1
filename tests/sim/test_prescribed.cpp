// Prescribed rigid motion: the profiles, and the Kane-Ryan-Banerjee spin-up of a
// cantilever clamped to a hub against the independent reference of tests/reference
// (scripts/reference/krb_spinup.py: Hermite finite elements with axial degrees of freedom
// and the geometrically exact strain, Radau IIA).
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "freeflex/sim/prescribed.hpp"
#include "support/reference_csv.hpp"

using namespace freeflex;

namespace {

/// The KRB cantilever: L = 10 m, ρA = 1.2 kg/m, EI = 14 000 N m², clamped at o = its root.
FlexibleBody krb_body(int noa, bool stiffening) {
  BeamProperties p;
  p.segments = {{10.0, 1.2, 14000.0}};
  p.reference_m = 0.0;
  return FlexibleBody(Beam(p), noa, {}, {}, stiffening);
}

SimulationOptions krb_options() {
  SimulationOptions o;
  o.duration_s = 20.0;
  o.output_step_s = 0.01;
  o.integrator.rtol = 1e-8;
  o.integrator.atol = 1e-10;
  o.energy_balance = true;
  return o;
}

}  // namespace

TEST_CASE("motion profiles: the spin-up and the table carry consistent derivatives", "[sim][prescribed]") {
  const MotionProfile s = MotionProfile::spin_up(4.0, 15.0);
  const double h = 1e-4;
  for (double t : {0.3, 4.0, 7.5, 14.2, 16.0}) {
    const Eigen::Vector3d a = s.at(t), p = s.at(t + h), m = s.at(t - h);
    // central differences, error h² θ'''/6 ~ 1e-8 (θ''' <= 2π Ω/Ts² = 0.11)
    CHECK((p(0) - m(0)) / (2 * h) == Approx(a(1)).margin(1e-7));
    CHECK((p(1) - m(1)) / (2 * h) == Approx(a(2)).margin(1e-7));
  }
  CHECK(s.at(15.0)(0) == Approx(30.0));  // Ω Ts / 2
  CHECK(s.at(20.0)(1) == 4.0);
  CHECK(s.peak_rate(20.0) == 4.0);
  // a quintic is reproduced exactly by its quintic Hermite interpolant
  auto f = [](double t) { return Eigen::Vector3d(1 + t - 2 * t * t * t + 0.5 * std::pow(t, 5),
                                                 1 - 6 * t * t + 2.5 * std::pow(t, 4), -12 * t + 10 * std::pow(t, 3)); };
  std::vector<double> ts{0.0, 0.4, 1.1, 2.0}, v, r, a;
  for (double t : ts) {
    v.push_back(f(t)(0));
    r.push_back(f(t)(1));
    a.push_back(f(t)(2));
  }
  const MotionProfile tab = MotionProfile::table(ts, v, r, a);
  for (double t : {0.1, 0.7, 1.5, 1.99})
    CHECK((tab.at(t) - f(t)).cwiseAbs().maxCoeff() < 1e-12);  // round-off of O(10) terms
  CHECK(tab.at(3.0)(1) == r.back());  // rate held after the end
  CHECK(tab.at(3.0)(2) == 0.0);
  CHECK_THROWS_AS(MotionProfile::table({0.0, 0.0}, {0, 0}, {0, 0}, {0, 0}), std::invalid_argument);
  CHECK_THROWS_AS(MotionProfile::spin_up(4.0, 0.0), std::invalid_argument);
}

TEST_CASE("a hub of radius r carries o around its centre", "[sim][prescribed]") {
  const PrescribedMotion m({}, {}, MotionProfile::spin_up(2.0, 3.0), 0.5);
  const double t = 1.3, h = 1e-5;
  const RigidState a = m.at(Instant::at(t)), p = m.at(Instant::at(t + h)), q = m.at(Instant::at(t - h));
  CHECK(a.pos.head<2>().norm() == Approx(0.5));
  // central differences, error ~h² |R'''| ~ 1e-10
  CHECK(((p.pos - q.pos) / (2 * h) - a.vel).cwiseAbs().maxCoeff() < 1e-8);
  CHECK(((p.vel - q.vel) / (2 * h) - a.acc).cwiseAbs().maxCoeff() < 1e-8);
}

TEST_CASE("KRB spin-up with stiffening: bounded, within 2 % of the peak of the reference", "[sim][prescribed]") {
  const auto ref = freeflex_test::reference_columns("krb_spinup_nonlinear.csv");
  const double rate = GENERATE(4.0, 6.0);
  const std::string col = rate == 4.0 ? "tip_v_os4_m" : "tip_v_os6_m";
  const FlexibleBody body = krb_body(6, true);
  const PrescribedMotion motion({}, {}, MotionProfile::spin_up(rate, 15.0));
  const SimulationResult full = simulate_prescribed(body, Excitation{}, motion, krb_options(), false);
  const SimulationResult lin = simulate_prescribed(body, Excitation{}, motion, krb_options(), true);
  INFO(full.message << lin.message);
  REQUIRE(full.ok());
  REQUIRE(lin.ok());
  const std::vector<double>& v = ref.at(col);
  REQUIRE(static_cast<int>(v.size()) == full.t.size());
  const Eigen::RowVectorXd tip = body.basis().value(10.0);
  double peak = 0.0, worst = 0.0, worst_lin = 0.0, t_min = 0.0, v_min = 0.0;
  for (int i = 0; i < full.t.size(); ++i) {
    const double u = tip.dot(full.z.row(i).tail(body.n())), ul = tip.dot(lin.z.row(i).tail(body.n()));
    peak = std::max(peak, std::abs(v[i]));
    worst = std::max(worst, std::abs(u - v[i]));
    worst_lin = std::max(worst_lin, std::abs(u - ul));
    if (u < v_min) v_min = u, t_min = full.t(i);
  }
  INFO("Ωs = " << rate << ": peak |v_ref| " << peak << " m, max |v - v_ref| " << worst << " m, min v " << v_min
               << " m at " << t_min << " s; |full - first order| " << worst_lin);
  // acceptance 1 of issue 14: 2 % of the peak (the strain measures differ by <0.4 %)
  CHECK(worst < 0.02 * peak);
  // under prescribed motion both models solve the same linear equation (eq. 14.10):
  // they differ by integration error (rtol 1e-8; measured 2e-8 of the peak)
  CHECK(worst_lin < 1e-6 * peak);
  // energy balance: E(t) − E(0) = work of the force holding the motion
  const FullModel fm(body);
  double e_worst = 0.0, w_peak = 0.0;
  for (int i = 0; i < full.t.size(); ++i) {
    Eigen::VectorXd x(2 * body.dofs());
    x << full.z.row(i).transpose(), full.z_dot.row(i).transpose();
    e_worst = std::max(e_worst, std::abs(fm.energy(x) - full.work_J(i)));
    w_peak = std::max(w_peak, std::abs(full.work_J(i)));
  }
  INFO("energy balance error " << e_worst << " J of work " << w_peak << " J");
  CHECK(e_worst < 1e-8 * w_peak);  // quadrature on the states' steps at rtol 1e-8: measured 5e-11
}

TEST_CASE("KRB spin-up without stiffening diverges and ends out of range", "[sim][prescribed]") {
  const double rate = GENERATE(4.0, 6.0);
  const auto lin_ref = freeflex_test::reference_columns(rate == 4.0 ? "krb_spinup_linear_os4.csv" : "krb_spinup_linear_os6.csv");
  const FlexibleBody body = krb_body(6, false);
  const PrescribedMotion motion({}, {}, MotionProfile::spin_up(rate, 15.0));
  for (bool first_order : {false, true}) {
    const SimulationResult r = simulate_prescribed(body, Excitation{}, motion, krb_options(), first_order);
    INFO("Ωs = " << rate << (first_order ? " first order: " : " full: ") << r.message);
    CHECK(r.status == IntegrationStatus::OutOfRange);
    CHECK_THAT(r.message, Catch::Matchers::Contains("grows without bound"));
    CHECK(r.t(r.t.size() - 1) < 20.0);
    // before it leaves, the linear model of the reference (exact cantilever modes) while |v| < 1 m
    const Eigen::RowVectorXd tip = body.basis().value(10.0);
    const std::vector<double>& v = lin_ref.at("tip_v_m");
    double worst = 0.0, scale = 0.0;
    for (int i = 0; i < r.t.size() && i < static_cast<int>(v.size()) && std::abs(v[i]) < 1.0; ++i) {
      worst = std::max(worst, std::abs(tip.dot(r.z.row(i).tail(body.n())) - v[i]));
      scale = std::max(scale, std::abs(v[i]));
    }
    INFO("max |v - v_linear_ref| " << worst << " of " << scale);
    // 6 cantilever functions (the exact modes) vs the reference's 16 modes, DOP853 at rtol
    // 1e-12: the higher modes' quasi-static share and integration error (measured 2.6e-7)
    CHECK(worst < 1e-5 * scale);
  }
}

TEST_CASE("prescribed full model without the energy balance: same states, no work column", "[sim][prescribed]") {
  // The global error estimate reruns the model without the energy balance (the work
  // quadrature): the run must not read a quadrature it did not integrate.
  const FlexibleBody body = krb_body(4, true);
  const PrescribedMotion motion(MotionProfile(), MotionProfile(), MotionProfile::spin_up(4.0, 15.0), 0.0);
  SimulationOptions o = krb_options();
  o.duration_s = 2.0;
  const SimulationResult with = simulate_prescribed(body, Excitation{}, motion, o, false);
  o.energy_balance = false;
  const SimulationResult without = simulate_prescribed(body, Excitation{}, motion, o, false);
  REQUIRE(with.ok());
  REQUIRE(without.ok());
  CHECK(with.work_J.size() == with.t.size());
  CHECK(without.work_J.size() == 0);
  CHECK((with.z - without.z).cwiseAbs().maxCoeff() == 0.0);  // quadratures stay out of the error test
}

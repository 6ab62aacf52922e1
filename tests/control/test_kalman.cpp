// The time-varying Kalman filter on the first-order model: its covariance against Monte
// Carlo error statistics (NEES), the truth simulated by a different method (fixed-step
// RK4 with the noise held over substeps, not the CVODES discretization the filter uses);
// sensors' output matrix against finite differences of the basis; bad input.
#include <catch2/catch.hpp>

#include <cmath>
#include <iostream>
#include <memory>

#include "freeflex/control/closed_loop.hpp"
#include "freeflex/control/lqg.hpp"
#include "freeflex/control/lqr.hpp"
#include "freeflex/control/metrics.hpp"
#include "freeflex/sim/simulate.hpp"
#include "support/bodies.hpp"

using namespace freeflex;

namespace {

FlexibleBody moment_body(int noa) { return freeflex_test::moment_body(noa, {0.01, 0.01}); }
using freeflex_test::moment_loads;

/// The moment example's first-order model about its nominal motion over [0, until_s],
/// with the hub torque and both thrusters as inputs (the models refer to the members).
struct MomentModel {
  MomentModel(int noa, double until_s) : body(moment_body(noa)), loads(moment_loads()) {
    SimulationOptions so;
    so.duration_s = until_s;
    pert = simulate_perturbation(body, loads, so);
    REQUIRE(pert.total.ok());
    model = std::make_unique<FirstOrderModel>(body, *pert.nominal, nominal_element_commands(loads, inputs), inputs);
  }
  FlexibleBody body;
  Excitation loads;
  std::vector<int> inputs{1, 2, 3};
  PerturbationResult pert;
  std::unique_ptr<FirstOrderModel> model;
};

/// Wilson–Hilferty: the p-quantile of chi-square with k degrees of freedom (relative
/// error < 1e-4 for k > 100; here k = 2000).
double chi2_quantile(double k, double z_p) {
  const double a = 2.0 / (9.0 * k);
  return k * std::pow(1.0 - a + z_p * std::sqrt(a), 3.0);
}

}  // namespace

TEST_CASE("Kalman filter: NEES of 200 Monte Carlo runs within the 95% chi-square bounds", "[control][kalman]") {
  const MomentModel mm(2, 1.5);
  const FlexibleBody& body = mm.body;
  const FirstOrderModel& model = *mm.model;
  const LtvSystem sys = ltv_system(model);
  const int n = model.state_size(), m = model.input_size();

  const std::vector<Sensor> sensors{{"gyro", Sensor::Type::GyroAttitude, 0.0, 1e-3},
                                    {"rate", Sensor::Type::GyroRate, 0.0, 1e-3},
                                    {"strain", Sensor::Type::Strain, 0.25, 1e-3},
                                    {"tip", Sensor::Type::TipDisplacement, 1.0, 1e-4}};
  const double fs = 100.0, Ts = 1.0 / fs, t_end = 1.5;
  const Eigen::MatrixXd C = output_matrix(body, sensors);
  const Eigen::MatrixXd V = measurement_variance(sensors, fs).asDiagonal();
  const Eigen::MatrixXd W = Eigen::Vector3d(1e-3, 1e-2, 1e-2).asDiagonal();
  const Eigen::MatrixXd P0 = Eigen::VectorXd::Constant(n, 1e-4).asDiagonal();
  const KalmanResult kf = design_kalman(sys, C, V, W, P0, 0.0, t_end, fs);
  REQUIRE(kf.ok());
  const int K = static_cast<int>(kf.model.t.size()) - 1;
  REQUIRE(K == 150);

  // The truth: x1' = A x1 + B w + g by RK4 with 20 substeps per sample, w held over each
  // substep with variance W/δ (white noise of intensity W band-limited at 1/δ); A, B, g
  // tabulated once at the stage times (the loads' steps at 0.5 s and 1 s are sample times).
  const int sub = 20;
  const double h = Ts / sub;
  struct Stage {
    Eigen::MatrixXd A, B;
    Eigen::VectorXd g;
  };
  std::vector<Stage> stages;  // 3 per substep: start, middle, end
  for (int k = 0; k < K; ++k)
    for (int j = 0; j < sub; ++j) {
      const double ta = k * Ts + j * h, mid = ta + 0.5 * h;
      for (double tt : {ta, mid, ta + h}) {
        const StateSpace ss = model.state_space(Instant{tt, mid});
        stages.push_back({ss.A, ss.B, ss.g});
      }
    }
  const Eigen::LLT<Eigen::MatrixXd> P0_llt(P0);
  const Eigen::VectorXd w_sd = (W.diagonal() / h).cwiseSqrt();
  const Eigen::VectorXd v_sd = V.diagonal().cwiseSqrt();
  const int runs = 200;
  Eigen::MatrixXd nees = Eigen::MatrixXd::Zero(K + 1, 1);
  NormalStream rng(20261125);
  for (int r = 0; r < runs; ++r) {
    Eigen::VectorXd e0(n);
    for (int i = 0; i < n; ++i) e0(i) = rng.next();
    Eigen::VectorXd x = P0_llt.matrixL() * e0;  // x1(0) ~ N(0, P0)
    Eigen::VectorXd xhat = Eigen::VectorXd::Zero(n);
    for (int k = 0; k <= K; ++k) {
      Eigen::VectorXd y = C * x;
      for (int i = 0; i < y.size(); ++i) y(i) += v_sd(i) * rng.next();
      xhat = kf.update(k, xhat, y);
      const Eigen::VectorXd e = x - xhat;
      nees(k) += e.dot(kf.P_post[k].ldlt().solve(e));
      if (k == K) break;
      xhat = kf.predict(k, xhat, Eigen::VectorXd::Zero(m));
      for (int j = 0; j < sub; ++j) {
        Eigen::VectorXd w(m);
        for (int i = 0; i < m; ++i) w(i) = w_sd(i) * rng.next();
        const Stage* s = &stages[static_cast<std::size_t>(3 * (k * sub + j))];
        auto f = [&](const Stage& st, const Eigen::VectorXd& xx) -> Eigen::VectorXd {
          return st.A * xx + st.B * w + st.g;
        };
        const Eigen::VectorXd k1 = f(s[0], x), k2 = f(s[1], x + 0.5 * h * k1), k3 = f(s[1], x + 0.5 * h * k2),
                              k4 = f(s[2], x + h * k3);
        x += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
      }
    }
  }
  nees /= runs;
  // Average NEES of M runs: M·ANEES ~ chi-square(M n) when the covariance is right.
  const double dof = static_cast<double>(runs) * n;
  const double lo = chi2_quantile(dof, -1.959964) / runs, hi = chi2_quantile(dof, 1.959964) / runs;
  int inside = 0;
  for (int k = 0; k <= K; ++k) inside += nees(k) >= lo && nees(k) <= hi;
  const double fraction = static_cast<double>(inside) / (K + 1);
  const double mean = nees.mean();
  std::cout << "Kalman NEES: n = " << n << ", 95% bounds [" << lo << ", " << hi << "], mean ANEES " << mean
            << ", min " << nees.minCoeff() << ", max " << nees.maxCoeff() << ", fraction of " << K + 1
            << " samples inside " << fraction << "\n";
  // 95% of the samples are expected inside; consecutive samples are correlated (the same
  // runs), so the fraction scatters more than a binomial: at least 90% asked.
  CHECK(fraction >= 0.90);
  // The time average of ANEES is n when the covariance is right: each sample's ANEES
  // scatters ±3.2% (1σ, sqrt(2/(M n))), their average over 1.5 s less; measured 10.10 (+1.0%).
  CHECK(mean == Approx(n).epsilon(0.03));
}

TEST_CASE("sensors: output matrix rows pick θ, θ', Φ''(x) q and Φ(x) q", "[control][kalman]") {
  const FlexibleBody body = moment_body(4);
  const std::vector<Sensor> sensors{{"gyro", Sensor::Type::GyroAttitude, 0.0, 0.0},
                                    {"rate", Sensor::Type::GyroRate, 0.0, 0.0},
                                    {"strain", Sensor::Type::Strain, 0.3, 0.0},
                                    {"tip", Sensor::Type::TipDisplacement, 1.0, 0.0}};
  const Eigen::MatrixXd C = output_matrix(body, sensors);
  const int N = body.dofs();
  REQUIRE(C.rows() == 4);
  REQUIRE(C.cols() == 2 * N);
  CHECK(C(0, 2) == 1.0);
  CHECK(C(1, N + 2) == 1.0);
  // curvature against a central difference of the basis values (h = 1e-4: error ~h² Φ'''' ~ 1e-6)
  const double x = body.beam().x_of(0.3), hh = 1e-4;
  const Eigen::RowVectorXd fd =
      (body.basis().value(x + hh) - 2.0 * body.basis().value(x) + body.basis().value(x - hh)) / (hh * hh);
  CHECK((C.row(2).segment(3, body.n()) - fd).cwiseAbs().maxCoeff() < 1e-4 * fd.cwiseAbs().maxCoeff());
  CHECK((C.row(3).segment(3, body.n()) - body.basis().value(body.beam().x_of(1.0))).norm() == 0.0);
  CHECK_THROWS_WITH(output_matrix(body, {{"bad", Sensor::Type::Strain, 1.5, 0.0}}),
                    Catch::Contains("position_m = 1.5, must be in [0, 1]"));
  CHECK_THROWS_WITH(output_matrix(body, {{"bad", Sensor::Type::GyroRate, 0.0, -1.0}}),
                    Catch::Contains("noise_density = -1"));
}

TEST_CASE("LQG on the full model: a gyro and two strain gauges come close to the exact state", "[control][kalman]") {
  // The moment example at NOA 4 with a hub torque and two tip thrusters; the TV-LQR's
  // weights of test_closed_loop.cpp, flown as a 500 Hz digital law with the exact state
  // and with the Kalman filter's estimate, seeded noise on the sensors and actuators.
  const MomentModel mm(4, 3.0);
  const FlexibleBody& body = mm.body;
  const Excitation& loads = mm.loads;
  const FirstOrderModel& model = *mm.model;
  SimulationOptions so;
  so.duration_s = 3.0;
  const SimulationResult open = simulate_full(body, loads, so);
  REQUIRE(open.ok());
  const Eigen::Vector3d limits(1.0, 2.0, 2.0);
  const Eigen::MatrixXd R = limits.cwiseInverse().cwiseAbs2().asDiagonal();
  const Eigen::MatrixXd Q = vibration_weight(body, 1.0, 10.0, 1.0);
  const TvlqrResult continuous = solve_tvlqr(model, 0.0, 3.0, Q, R);
  REQUIRE(continuous.ok());
  const double fs = 500.0;
  const std::vector<Sensor> sensors{{"gyro", Sensor::Type::GyroAttitude, 0.0, 1e-5},
                                    {"strain_a", Sensor::Type::Strain, 0.75, 1e-5},
                                    {"strain_b", Sensor::Type::Strain, 0.25, 1e-5}};
  const Eigen::Vector3d w_density(1e-3, 1e-3, 1e-3);
  const int n = model.state_size();
  const KalmanResult kf = design_kalman(ltv_system(model), output_matrix(body, sensors),
                                        measurement_variance(sensors, fs).asDiagonal(),
                                        Eigen::MatrixXd(w_density.cwiseAbs2().asDiagonal()),
                                        Eigen::MatrixXd::Identity(n, n) * 1e-6, 0.0, 3.0, fs);
  REQUIRE(kf.ok());
  const TvlqrResult law = solve_discrete_tvlqr(kf.model, Q, R, continuous.Qf);
  REQUIRE(law.ok());
  PlantOptions po;
  po.process_noise_density = w_density;
  po.seed = 42;
  SampledLoopOptions lo;
  lo.sample_rate_hz = fs;
  lo.limits = limits;
  lo.feedback = SampledLoopOptions::Feedback::FullState;
  const SampledLoopResult exact = simulate_sampled_loop(body, model, loads, {}, law, &kf, sensors, po, lo);
  lo.feedback = SampledLoopOptions::Feedback::Lqg;
  const SampledLoopResult lqg = simulate_sampled_loop(body, model, loads, {}, law, &kf, sensors, po, lo);
  REQUIRE(exact.ok());
  REQUIRE(lqg.ok());
  MetricTargets target;
  target.theta_target = 3.0;
  auto energy = [&](const Eigen::VectorXd& t, const Eigen::MatrixXd& z, const Eigen::MatrixXd& zd) {
    return response_metrics(body, t, z, zd, Eigen::MatrixXd(), target).mean_vibration_energy_J;
  };
  const double e_open = energy(open.t, open.z, open.z_dot), e_exact = energy(exact.t, exact.z, exact.z_dot),
               e_lqg = energy(lqg.t, lqg.z, lqg.z_dot);
  std::cout << "LQG on the moment example (mean E_vib over the last second): open loop " << e_open
            << " J, digital TV-LQR exact state " << e_exact << " J, LQG " << e_lqg << " J (ratio "
            << e_lqg / e_exact << ")\n";
  CHECK(e_lqg < 2e-3 * e_open);  // far below the open loop: measured 7.3e-4 of it (seeded noise sets the floor)
  CHECK(e_lqg < 3.0 * e_exact);  // the estimate costs a little: measured 1.59x the exact state
  // A plant 6 ms late (3 samples) and lagging 2 ms: the law unaware of the delay against
  // the law that predicts over it (LQG with delay_known).
  po.delay_s = 0.006;
  po.lag_s = 0.002;
  const SampledLoopResult unaware = simulate_sampled_loop(body, model, loads, {}, law, &kf, sensors, po, lo);
  lo.delay_known = true;
  const SampledLoopResult aware = simulate_sampled_loop(body, model, loads, {}, law, &kf, sensors, po, lo);
  REQUIRE(unaware.ok());
  REQUIRE(aware.ok());
  const double e_unaware = energy(unaware.t, unaware.z, unaware.z_dot), e_aware = energy(aware.t, aware.z, aware.z_dot);
  std::cout << "LQG with a 6 ms delay and a 2 ms lag: unaware " << e_unaware << " J, predicting over the delay "
            << e_aware << " J\n";
  CHECK(e_aware < 1e-2 * e_unaware);  // unaware the loop goes unstable (measured 0.116 J), aware 3.1e-5 J
  CHECK(e_aware < 3.0 * e_lqg);       // nearly what the undelayed plant gets (measured 0.97x)
  lo.delay_known = false;
  po.delay_s = 0.0;
  po.lag_s = 0.0;
  // the filter's error at the end is within a few of its 1σ on the elastic coordinates
  const Eigen::VectorXd err = lqg.estimate_error.row(lqg.estimate_error.rows() - 1).transpose();
  const Eigen::VectorXd sd = kf.P_post.back().diagonal().cwiseSqrt();
  for (int i = 3; i < 3 + body.n(); ++i) CHECK(std::abs(err(i)) < 4.0 * sd(i));  // 4σ: P(|e| > 4σ) = 6e-5 per coordinate
}

TEST_CASE("observability: which sensors see which modes (the filter's 1σ at the end)", "[control][kalman]") {
  // The moment example at NOA 4 (q1, q3 symmetric about o, q2, q4 antisymmetric), 1 s of
  // filtering at 200 Hz from a prior of 1e-3 on every coordinate, process noise on the
  // hub torque and the thrusters. A coordinate no sensor sees keeps (or grows) its prior;
  // one a sensor sees falls to the sensor's noise level.
  const MomentModel mm(4, 1.5);
  const FlexibleBody& body = mm.body;
  const FirstOrderModel& model = *mm.model;
  const int n = model.state_size();
  const double fs = 200.0;
  const Eigen::MatrixXd W = Eigen::Vector3d(1e-6, 1e-6, 1e-6).asDiagonal();
  auto final_std = [&](const std::vector<Sensor>& sensors) {
    const KalmanResult kf =
        design_kalman(ltv_system(model), output_matrix(body, sensors), measurement_variance(sensors, fs).asDiagonal(),
                      W, Eigen::MatrixXd::Identity(n, n) * 1e-6, 0.0, 1.0, fs);
    REQUIRE(kf.ok());
    return Eigen::VectorXd(kf.P_post.back().diagonal().segment(3, body.n()).cwiseSqrt());
  };
  const Sensor gyro{"gyro", Sensor::Type::GyroAttitude, 0.0, 1e-5};
  const Sensor left{"strain_l", Sensor::Type::Strain, 0.25, 1e-5}, right{"strain_r", Sensor::Type::Strain, 0.75, 1e-5};
  const Sensor tip{"tip", Sensor::Type::TipDisplacement, 1.0, 1e-5};
  const std::vector<std::pair<std::string, std::vector<Sensor>>> sets{
      {"gyro", {gyro}}, {"strain 0.25", {left}}, {"strains 0.25, 0.75", {left, right}},
      {"gyro + strains", {gyro, left, right}}, {"tip 1.0", {tip}}};
  std::vector<Eigen::VectorXd> sd;
  for (const auto& [name, s] : sets) {
    sd.push_back(final_std(s));
    std::cout << "observability: " << name << ": 1σ of q1..q4 at 1 s = " << sd.back().transpose() << '\n';
  }
  // Measured (q1..q4): gyro 1.1e-3, 7.1e-5, 1.0e-4, 1.3e-5; strains at 0.25 and 0.75 m
  // 7.5e-6, 1.6e-4, 8.7e-7, 1.2e-5; both 7.5e-6, 4.4e-5, 8.7e-7, 3.5e-6.
  // The gyro sees the antisymmetric coordinates (they turn the beam about o), not the
  // first symmetric one, which keeps its prior 1e-3 (q3 it sees a little through the
  // turn's coupling of rotation and symmetric bending).
  CHECK(sd[0](0) > 0.5e-3);
  CHECK(sd[0](1) < 0.1e-3);
  CHECK(sd[0](3) < 0.1e-3);
  // Two gauges placed symmetrically pin down the symmetric coordinates; the
  // antisymmetric ones they confuse with the attitude they do not measure.
  CHECK(sd[2](0) < 1e-5);
  CHECK(sd[2](2) < 1e-5);
  CHECK(sd[2](1) > 1e-4);
  // Together: every coordinate at least as well as with either set alone (a sensor added
  // never loses information), all below 5e-5.
  for (int i = 0; i < 4; ++i) {
    CHECK(sd[3](i) <= std::min(sd[0](i), sd[2](i)) * (1.0 + 1e-9));
    CHECK(sd[3](i) < 5e-5);
  }
}

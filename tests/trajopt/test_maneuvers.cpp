// Optimal maneuvers against known answers: closed forms for a torque on a rigid beam,
// the convergence order of the trapezoidal rule, a nonlinear two-thruster slew replayed
// open loop through the zero-order simulator, minimum time, an unreachable target, mesh
// refinement and warm starts.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <thread>

#include "freeflex/dynamics/zero_order.hpp"
#include "freeflex/trajopt/replay.hpp"
#include "freeflex/trajopt/solve.hpp"
#include "support/slew.hpp"

using namespace freeflex;

namespace {

/// The paper's beam (1 m, 1 kg, EI 1, o at the centre: I_o = 1/12) with a torque at o.
FlexibleBody torque_body() {
  return FlexibleBody(Beam(BeamProperties::uniform(1.0, 1.0, 1.0)), 2,
                      {{"Mz", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false}});
}

/// Rest to rest rotation by dtheta in T with an unbounded torque, minimum ∫τ² dt.
ManeuverProblem rotation(double dtheta, double T) {
  ManeuverProblem p;
  p.actuators = {0};
  p.u_min = Eigen::VectorXd::Constant(1, -ManeuverProblem::inf);
  p.u_max = Eigen::VectorXd::Constant(1, ManeuverProblem::inf);
  p.x_final(2) = dtheta;
  p.duration_s = T;
  return p;
}

using freeflex_test::slew;           // the two-thruster slew (tests/support/slew.hpp)
using freeflex_test::thruster_body;

/// The end state of the open-loop replay (ZeroOrderModel under r's commands, CVODES).
Eigen::VectorXd replay(const FlexibleBody& body, const ManeuverProblem& p, const TrajoptResult& r) {
  IntegratorOptions io;
  io.rtol = 1e-10;  // far below the 1e-4 the tests ask of the replay
  io.atol = 1e-12;
  const IntegrationResult ir = replay_open_loop(body, p, r, io);
  REQUIRE(ir.ok());
  return ir.x.row(ir.x.rows() - 1).transpose();
}

}  // namespace

TEST_CASE("minimum-energy rotation: Hermite-Simpson is exact at any N", "[trajopt]") {
  const FlexibleBody body = torque_body();
  const double I_o = body.integrals().I_o, dth = 1.2, T = 2.0;
  REQUIRE(I_o == Approx(1.0 / 12.0).epsilon(1e-12));  // closed-form modal integral, round-off only
  const double J_exact = 12.0 * I_o * I_o * dth * dth / (T * T * T);
  for (Transcription tr : {Transcription::HermiteSimpson, Transcription::HermiteSimpsonCompressed})
  for (int N : {1, 5, 20}) {
    TrajoptOptions o;
    o.transcription = tr;
    o.intervals = N;
    const TrajoptResult r = solve_maneuver(body, rotation(dth, T), o);
    INFO(to_string(tr) << ", N = " << N << ": " << r.message);
    REQUIRE(r.ok());
    // The optimum (cubic θ, linear τ) lies in the HS trial space and Simpson's rule
    // integrates τ² exactly: only Ipopt's tolerance (tol 1e-8) remains.
    CHECK(std::abs(r.objective - J_exact) < 1e-8 * J_exact + 1e-12);
    CHECK(r.max_defect < 1e-9);  // constraint violation at convergence, Ipopt tol 1e-8
    for (double t : {0.0, 0.3, 1.0, 1.77, 2.0}) {
      const double tau = I_o * dth * (6.0 - 12.0 * t / T) / (T * T);  // θ'' I_o of the cubic
      CHECK(std::abs(r.control_at(t)(0) - tau) < 1e-6);  // control error ~ multiplier accuracy
    }
  }
}

TEST_CASE("solves on one thread and on two at once agree to the bit", "[trajopt]") {
  // Each thread keeps one registry of Ipopt's options for all its solves
  // (trajopt/ipopt_adapter.cpp): the second solve on a thread, and solves on two threads
  // at once, must give what the first solve gave.
  const FlexibleBody body = torque_body();
  TrajoptOptions o;
  o.intervals = 8;
  const ManeuverProblem p = rotation(1.2, 2.0);
  const TrajoptResult first = solve_maneuver(body, p, o);
  REQUIRE(first.ok());
  const TrajoptResult again = solve_maneuver(body, p, o);
  TrajoptResult a, b;
  std::thread ta([&] { a = solve_maneuver(body, p, o); });
  std::thread tb([&] { b = solve_maneuver(body, p, o); });
  ta.join();
  tb.join();
  for (const TrajoptResult* r : std::initializer_list<const TrajoptResult*>{&again, &a, &b}) {
    REQUIRE(r->ok());
    CHECK(r->iterations == first.iterations);
    CHECK(r->objective == first.objective);
    CHECK(r->u == first.u);
  }
}

TEST_CASE("minimum-energy rotation: the trapezoidal rule converges at second order", "[trajopt]") {
  const FlexibleBody body = torque_body();
  const double I_o = body.integrals().I_o, dth = 1.2, T = 2.0;
  const double J_exact = 12.0 * I_o * I_o * dth * dth / (T * T * T);
  const std::vector<int> Ns = {10, 20, 40, 80};
  std::vector<double> err;
  std::ostringstream table;
  table << "trapezoidal min-energy rotation, J* = " << J_exact << "\n   N   J - J*       ratio\n";
  for (int N : Ns) {
    TrajoptOptions o;
    o.transcription = Transcription::Trapezoidal;
    o.intervals = N;
    const TrajoptResult r = solve_maneuver(body, rotation(dth, T), o);
    REQUIRE(r.ok());
    err.push_back(r.objective - J_exact);
    char line[96];
    std::snprintf(line, sizeof line, "%4d  %.4e  %s\n", N, err.back(),
                  err.size() > 1 ? std::to_string(err[err.size() - 2] / err.back()).c_str() : "");
    table << line;
  }
  WARN(table.str());
  for (std::size_t i = 0; i + 1 < err.size(); ++i) {
    CHECK(err[i] > 0.0);  // a coarser discrete control cannot do better here
    const double ratio = err[i] / err[i + 1];
    CHECK(ratio > 3.5);  // halving h divides an O(h²) error by 4; ±0.5 for higher-order terms
    CHECK(ratio < 4.5);
  }
}

TEST_CASE("minimum-time rotation with a bounded torque matches the bang-bang time", "[trajopt]") {
  const FlexibleBody body = torque_body();
  const double I_o = body.integrals().I_o, dth = 1.0, tau_max = 0.8;
  const double T_exact = 2.0 * std::sqrt(I_o * dth / tau_max);
  ManeuverProblem p = rotation(dth, 1.0);
  p.u_min(0) = -tau_max;
  p.u_max(0) = tau_max;
  p.free_time = true;
  p.t_min_s = 0.1;
  p.t_max_s = 5.0;
  p.w_energy = 0.0;
  p.w_time = 1.0;
  for (Transcription tr :
       {Transcription::HermiteSimpson, Transcription::HermiteSimpsonCompressed, Transcription::Trapezoidal}) {
    TrajoptOptions o;
    o.transcription = tr;
    o.intervals = 100;
    const TrajoptResult r = solve_maneuver(body, p, o);
    INFO(to_string(tr) << ": " << r.message << ", T = " << r.duration_s << ", exact " << T_exact);
    REQUIRE(r.ok());
    // the switch needs one interval to cross from +τmax to −τmax: O(h²) relative loss
    CHECK(std::abs(r.duration_s / T_exact - 1.0) < 1e-3);
    CHECK(r.objective == Approx(r.duration_s).epsilon(1e-12));  // J = w_time T exactly, nothing else weighs
  }
}

TEST_CASE("two-thruster slew at minimum energy, replayed open loop", "[trajopt]") {
  const FlexibleBody body = thruster_body();
  const ManeuverProblem p = slew();
  TrajoptOptions o;
  o.transcription = Transcription::HermiteSimpson;
  o.intervals = 100;  // default guess: straight line in state space, zero thrust
  const TrajoptResult r = solve_maneuver(body, p, o);
  INFO(r.message);
  REQUIRE(r.ok());
  CHECK(r.max_defect < 1e-9);  // Ipopt tol 1e-8 on the scaled constraints
  CHECK(r.u.cwiseAbs().maxCoeff() <= 1.0 + 1e-8);  // bounds hold up to Ipopt's bound relaxation
  REQUIRE(r.trajectory);
  CHECK(r.t.size() == 101);
  CHECK(r.u_mid.rows() == 100);

  const Eigen::VectorXd xT = replay(body, p, r);
  const double pos_err = (xT.head<2>() - p.x_final.head<2>()).cwiseAbs().maxCoeff();
  const double ang_err = std::abs(xT(2) - p.x_final(2));
  const double rate_err = (xT.tail<3>() - p.x_final.tail<3>()).cwiseAbs().maxCoeff();
  WARN("slew, HS N = 100: J = " << r.objective << " N^2 s, " << r.iterations << " iterations, "
                                << r.solve_time_s << " s; open-loop replay misses the target by " << pos_err
                                << " m, " << ang_err << " rad, " << rate_err << " m/s or rad/s");
  CHECK(pos_err < 1e-4);   // the accuracy the maneuver issue requires of an HS N = 100 solution
  CHECK(ang_err < 1e-4);   // same
  CHECK(rate_err < 1e-4);  // same
  // HS is O(h⁴): observed 3e-8, 3e-9 and 1e-8 at N = 100; 1e-6 catches an order lost
  CHECK(std::max({pos_err, ang_err, rate_err}) < 1e-6);
  // The replay reports its start at t = 0 and its end at T.
  IntegratorOptions io;
  const IntegrationResult ir = replay_open_loop(body, p, r, io);
  REQUIRE(ir.ok());
  CHECK(ir.t.size() == 2);
  CHECK(ir.t(1) == r.duration_s);
  CHECK(ir.steps > 0);
  // A result without a trajectory cannot be replayed: a clear error, not a crash.
  CHECK_THROWS_WITH(replay_open_loop(body, p, TrajoptResult{}, io), Catch::Contains("no trajectory"));
  // The trajectory says the same as the replay: its error estimate is small (observed
  // 2.3e-7, the size of the replay's miss; 1e-5 is 40 times that, so a lost order shows).
  CHECK(r.max_error_estimate < 1e-5);

  // The compressed form is the same discretization: the same optimum.
  o.transcription = Transcription::HermiteSimpsonCompressed;
  const TrajoptResult rc = solve_maneuver(body, p, o);
  REQUIRE(rc.ok());
  CHECK(rc.objective == Approx(r.objective).epsilon(1e-9));  // both converged to tol 1e-8
  // controls are a flat direction of the cost where the thrust saturates: they agree to the
  // solver tolerance only through the dynamics (observed 5e-6)
  CHECK((rc.u - r.u).cwiseAbs().maxCoeff() < 5e-5);
  CHECK((rc.u_mid - r.u_mid).cwiseAbs().maxCoeff() < 5e-5);
  CHECK((rc.x_mid - r.x_mid).cwiseAbs().maxCoeff() < 1e-6);  // states are pinned by the dynamics: tighter
  CHECK((replay(body, p, rc) - p.x_final).cwiseAbs().maxCoeff() < 1e-4);  // as for the separated form

  // The trapezoidal solution of the same problem converges too, to a nearby cost.
  o.transcription = Transcription::Trapezoidal;
  const TrajoptResult rt = solve_maneuver(body, p, o);
  REQUIRE(rt.ok());
  CHECK(std::abs(rt.objective - r.objective) < 0.01 * r.objective);  // O(h²) ~ 1e-3 relative at N = 100
}

TEST_CASE("two-thruster slew at minimum time", "[trajopt]") {
  const FlexibleBody body = thruster_body();
  ManeuverProblem p = slew();
  p.free_time = true;
  p.t_min_s = 0.5;
  p.t_max_s = 10.0;
  p.w_energy = 0.0;
  p.w_time = 1.0;
  TrajoptOptions o;
  o.transcription = Transcription::HermiteSimpson;
  o.intervals = 100;
  const TrajoptResult r = solve_maneuver(body, p, o);
  INFO(r.message);
  REQUIRE(r.ok());
  WARN("slew, minimum time, HS N = 100: T* = " << r.duration_s << " s (" << r.iterations << " iterations, "
                                               << r.solve_time_s << " s)");
  // Faster than the 3 s energy-optimal slew, slower than thrusting straight at 2 N
  // (1.118 m rest to rest needs 2 sqrt(1.118 / 2) = 1.50 s) since the body must turn.
  CHECK(r.duration_s < 3.0);
  CHECK(r.duration_s > 1.5);
  CHECK(r.duration_s > p.t_min_s + 0.1);  // an interior optimum, not the bound
  // Bang-bang thrust: most knots sit on a bound.
  int on_bound = 0;
  // an interior-point optimum stops ~tol (1e-8) inside an active bound; 1e-4 tells active from interior
  for (Eigen::Index i = 0; i < r.u.size(); ++i) on_bound += std::abs(std::abs(r.u(i)) - 1.0) < 1e-4;
  CHECK(on_bound > r.u.size() / 2);
  const Eigen::VectorXd xT = replay(body, p, r);
  INFO("replay end state " << xT.transpose());
  CHECK((xT - p.x_final).cwiseAbs().maxCoeff() < 1e-3);  // bang-bang kinks cost accuracy; still O(h⁴) between
}

TEST_CASE("an unreachable target ends infeasible, not as a solution", "[trajopt]") {
  const FlexibleBody body = torque_body();
  // |τ| <= 0.1 N m turns I_o = 1/12 by at most τ T²/(4 I_o) = 0.3 rad rest to rest in 1 s.
  ManeuverProblem p = rotation(10.0, 1.0);
  p.u_min(0) = -0.1;
  p.u_max(0) = 0.1;
  for (Transcription tr :
       {Transcription::HermiteSimpson, Transcription::HermiteSimpsonCompressed, Transcription::Trapezoidal}) {
    TrajoptOptions o;
    o.transcription = tr;
    o.intervals = 20;
    const TrajoptResult r = solve_maneuver(body, p, o);
    INFO(to_string(tr) << ": " << r.message);
    CHECK_FALSE(r.ok());
    CHECK(r.status == TrajoptStatus::Infeasible);
    CHECK(r.message.find("not a solution") != std::string::npos);
    CHECK(r.max_defect > 1e-3);  // the returned point violates the dynamics
  }
}

TEST_CASE("mesh refinement drives the error estimate below its tolerance", "[trajopt]") {
  const FlexibleBody body = thruster_body();
  const ManeuverProblem p = slew();
  TrajoptOptions o;
  o.transcription = Transcription::Trapezoidal;
  o.intervals = 20;
  o.mesh_refinements = 6;
  o.mesh_tolerance = 1e-4;
  o.coarse_start = false;  // the first round from the straight line: the warm rounds are compared with a cold one
  const TrajoptResult r = solve_maneuver(body, p, o);
  INFO(r.message);
  REQUIRE(r.ok());
  REQUIRE(r.rounds.size() >= 2);
  std::ostringstream s;
  for (const MeshRound& m : r.rounds)
    s << "N = " << m.intervals << ": " << m.iterations << " iterations, max error estimate " << m.max_error_estimate
      << ", J = " << m.objective << "\n";
  INFO(s.str());
  CHECK(r.rounds.front().max_error_estimate > o.mesh_tolerance);  // refinement had work to do
  CHECK(r.max_error_estimate <= o.mesh_tolerance);
  CHECK(r.intervals == r.rounds.back().intervals);
  CHECK(r.intervals > 20);
  for (std::size_t i = 1; i < r.rounds.size(); ++i) {
    CHECK(r.rounds[i].intervals > r.rounds[i - 1].intervals);
    CHECK(r.rounds[i].iterations < r.rounds[0].iterations);  // warm starts pay off
  }
  // Local refinement beats uniform: fewer intervals than a uniform mesh of the same finest h.
  double h_min = 1.0;
  for (Eigen::Index k = 0; k + 1 < r.t.size(); ++k) h_min = std::min(h_min, r.t(k + 1) - r.t(k));
  CHECK(r.intervals < static_cast<int>(std::round(r.duration_s / h_min)));
}

TEST_CASE("warm starts and control guesses", "[trajopt]") {
  const FlexibleBody body = thruster_body();
  const ManeuverProblem p = slew();
  TrajoptOptions o;
  o.transcription = Transcription::HermiteSimpsonCompressed;
  o.intervals = 40;
  o.coarse_start = false;  // from the straight line: the baseline of the starts below
  const TrajoptResult cold = solve_maneuver(body, p, o);
  REQUIRE(cold.ok());
  CHECK_FALSE(cold.warm_started);

  // By default a problem given no guess starts from its own solution on an eighth of the
  // mesh (at least 10 intervals: 10 here) and continues at mu_init 1e-6: the same optimum, fewer
  // iterations on the fine mesh.
  TrajoptOptions coarse = o;
  coarse.coarse_start = true;
  const TrajoptResult c = solve_maneuver(body, p, coarse);
  REQUIRE(c.ok());
  CHECK(c.warm_started);
  CHECK(c.warm_start_iterations > 0);
  INFO("iterations: cold " << cold.iterations << ", coarse start " << c.iterations << " + " << c.warm_start_iterations);
  CHECK(c.iterations < cold.iterations);
  CHECK(c.objective == Approx(cold.objective).epsilon(1e-8));  // one optimum, to Ipopt's tol 1e-8

  // A coarse solve that fails (here: out of Ipopt's own iterations, which the coarse
  // solve keeps, capped at 500) leaves the straight line.
  TrajoptOptions starved = coarse;
  starved.ipopt_options = {{"max_iter", "3"}};
  const TrajoptResult e = solve_maneuver(body, p, starved);
  CHECK(e.warm_start_iterations == 3);
  CHECK_FALSE(e.warm_started);

  // A previous solution on another mesh and transcription is interpolated.
  TrajoptOptions warm = o;
  warm.intervals = 60;
  warm.guess.solution = cold.trajectory;
  warm.ipopt_options = {{"mu_init", "1e-6"}};
  const TrajoptResult w = solve_maneuver(body, p, warm);
  REQUIRE(w.ok());
  CHECK(w.iterations < cold.iterations);
  CHECK(w.objective == Approx(cold.objective).epsilon(1e-4));  // HS: O(h⁴) between N = 40 and 60

  // A pulse guess with a rollout of the dynamics (the paper's ±1 pulse on the right tip).
  TrajoptOptions pulse = o;
  pulse.guess.control = [](double t) { return Eigen::Vector2d(0.0, t < 0.5 ? 1.0 : (t < 1.0 ? -1.0 : 0.0)); };
  pulse.guess.rollout = true;
  const TrajoptResult r = solve_maneuver(body, p, pulse);
  REQUIRE(r.ok());
  CHECK(r.objective == Approx(cold.objective).epsilon(1e-8));  // the same local optimum
}

TEST_CASE("the collocation trajectory is a consistent RigidTrajectory", "[trajopt]") {
  const FlexibleBody body = thruster_body();
  TrajoptOptions o;
  o.intervals = 30;
  for (Transcription tr :
       {Transcription::HermiteSimpson, Transcription::HermiteSimpsonCompressed, Transcription::Trapezoidal}) {
    o.transcription = tr;
    const TrajoptResult r = solve_maneuver(body, slew(), o);
    REQUIRE(r.ok());
    const CollocationTrajectory& traj = *r.trajectory;
    CHECK(traj.t_begin() == 0.0);
    CHECK(traj.t_end() == Approx(3.0).epsilon(1e-14));  // T fixed; Σ σ_k = 1 up to round-off
    CHECK(traj.breakpoints().size() == 29);
    const RigidDynamics& dyn = traj.dynamics().rigid();
    for (int k = 0; k <= 30; ++k) {  // knots are interpolated exactly
      const RigidState s = traj.at(Instant::at(r.t(k)));
      // Hermite basis at s = 0 or 1 returns the knot values up to round-off
      CHECK((s.pos - r.x.row(k).head<3>().transpose()).cwiseAbs().maxCoeff() < 1e-14);
      CHECK((s.vel - r.x.row(k).tail<3>().transpose()).cwiseAbs().maxCoeff() < 1e-14);
      CHECK((traj.control_at(r.t(k)) - r.u.row(k).transpose()).cwiseAbs().maxCoeff() < 1e-14);  // same
    }
    if (has_midpoints(tr))
      for (int k = 0; k < 30; ++k) {  // the cubic passes through the midpoint states (defect ~ tol)
        CHECK((traj.state_at(r.t_mid(k)) - r.x_mid.row(k).transpose()).cwiseAbs().maxCoeff() < 1e-9);
        // the quadratic through knot, midpoint, knot: exact at s = 1/2 up to round-off
        CHECK((traj.control_at(r.t_mid(k)) - r.u_mid.row(k).transpose()).cwiseAbs().maxCoeff() < 1e-14);
      }
    const ZeroOrderModel zero(body);  // the simulation's rigid model, another code path than dyn
    for (double t : {0.01, 1.234, 2.99}) {  // acceleration = the model at the interpolated point
      const RigidState s = traj.at(Instant::at(t));
      Eigen::VectorXd commands = Eigen::VectorXd::Zero(body.elements().size());
      const Eigen::VectorXd u = traj.control_at(t);
      for (int k = 0; k < dyn.nu(); ++k) commands(dyn.actuators()[k]) = u(k);
      const Eigen::Vector3d acc = zero.acceleration(traj.state_at(t), commands);
      // two solution paths of the same 3 x 3 system (see test_rigid_dynamics): round-off of O(1) values
      CHECK((s.acc - acc).cwiseAbs().maxCoeff() < 1e-12);
    }
    CHECK(traj.control_at(-0.1).isZero());
    CHECK(traj.control_at(3.1).isZero());
  }
}

TEST_CASE("Ipopt reaches the same optimum with freeflex's LDLT as with MUMPS", "[trajopt][ldlt]") {
  // the same NLP factored two ways: each KKT solve agrees to round-off, so Ipopt takes the
  // same iterations to the same point (measured: |dJ|/J <= 2.0e-16 and |du| <= 1.2e-15 N
  // over the four cases, the same iteration counts); the bounds leave room for round-off
  // growing over ~20 iterations, far below Ipopt's tolerance (tol 1e-8)
  const FlexibleBody body = thruster_body();
  ManeuverProblem energy = slew();
  ManeuverProblem fastest = slew();  // saturated arcs and a free duration
  fastest.free_time = true;
  fastest.t_min_s = 0.5;
  fastest.t_max_s = 10.0;
  fastest.w_energy = 0.0;
  fastest.w_time = 1.0;
  fastest.w_smooth = 1e-4;
  for (const ManeuverProblem& p : {energy, fastest})
    for (Transcription tr : {Transcription::Trapezoidal, Transcription::HermiteSimpsonCompressed}) {
      TrajoptOptions o;
      o.transcription = tr;
      o.intervals = 40;
      o.linear_solver = LinearSolver::Ldlt;
      const TrajoptResult a = solve_maneuver(body, p, o);
      o.linear_solver = LinearSolver::Mumps;
      const TrajoptResult b = solve_maneuver(body, p, o);
      REQUIRE(a.ok());
      REQUIRE(b.ok());
      INFO(to_string(tr) << (p.free_time ? ", minimum time" : ", minimum energy") << ": J " << a.objective << " vs "
                         << b.objective << ", iterations " << a.iterations << " vs " << b.iterations << ", |dJ|/J "
                         << std::abs(a.objective - b.objective) / std::abs(b.objective) << ", max |du| "
                         << (a.u - b.u).cwiseAbs().maxCoeff());
      CHECK(a.linear_solver == LinearSolver::Ldlt);
      CHECK(a.iterations == b.iterations);
      CHECK(std::abs(a.objective - b.objective) < 1e-12 * std::abs(b.objective));
      CHECK((a.u - b.u).cwiseAbs().maxCoeff() < 1e-10);
    }
}

TEST_CASE("a mesh too coarse for the rigid motion is flagged by flying its commands", "[trajopt]") {
  // The two-thruster slew on 10 trapezoidal intervals: Ipopt meets every constraint, but
  // the commands flown on the zero-order model end 4.3 cm from the optimizer's final state
  // (measured), over 1% of the 1.1 m move. On 100 Hermite-Simpson intervals 3e-8 m.
  const FlexibleBody body = thruster_body();
  const ManeuverProblem p = slew();
  TrajoptOptions o;
  o.transcription = Transcription::Trapezoidal;
  o.intervals = 10;
  const TrajoptResult coarse = solve_maneuver(body, p, o);
  REQUIRE(coarse.ok());
  const ReplayCheck c = check_replay(body, p, coarse);
  INFO(c.message);
  REQUIRE(c.ok);
  CHECK(c.flagged);
  CHECK(c.position_miss_m > 0.01 * c.position_scale_m);
  CHECK(c.position_scale_m == Approx(std::hypot(1.0, 0.5)));  // the move, reached to Ipopt's tolerance
  CHECK_THAT(c.message, Catch::Contains("does not resolve the rigid motion"));
  // the miss is the integration of the same commands: check it against replay_open_loop
  IntegratorOptions io;
  io.rtol = 1e-10;
  io.atol = 1e-12;
  io.method = IntegratorOptions::Method::Verner98;
  const IntegrationResult ir = replay_open_loop(body, p, coarse, io);
  REQUIRE(ir.ok());
  const Eigen::RowVectorXd end = ir.x.bottomRows(1);
  CHECK(c.position_miss_m ==
        Approx((end.head<2>() - coarse.x.bottomRows(1).leftCols<2>()).norm()).epsilon(1e-12));  // the same integration
  // and another integrator (CVODES's Adams, tighter) flies the commands to the same end:
  // both integration errors are of the order of rtol times the 1 m scale
  io.method = IntegratorOptions::Method::Adams;
  io.rtol = 1e-12;
  io.atol = 1e-14;
  const IntegrationResult adams = replay_open_loop(body, p, coarse, io);
  REQUIRE(adams.ok());
  CHECK((adams.x.bottomRows(1) - end).cwiseAbs().maxCoeff() < 1e-8);

  o.transcription = Transcription::HermiteSimpson;
  o.intervals = 100;
  const TrajoptResult fine = solve_maneuver(body, p, o);
  REQUIRE(fine.ok());
  const ReplayCheck f = check_replay(body, p, fine);
  REQUIRE(f.ok);
  CHECK(!f.flagged);
  CHECK(f.message.empty());
  CHECK(f.position_miss_m < 1e-6);  // HS is O(h^4): 3e-8 observed
}

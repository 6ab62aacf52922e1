// Example: an optimal rigid slew from the zero-order model, through the library API.
//
// Scenario: the paper's beam (1 m, 1 kg, EI = 1 N m^2) with two thrusters fixed to the
// body, pushing along body y at the tips (|u| <= 1 N each), moves from rest at the origin
// to rest at (1 m, 0.5 m, 90 deg) in 3 s at least energy (∫uᵀu dt), Hermite-Simpson
// collocation with 100 intervals, solved by Ipopt from the trivial guess; then the least
// time for the same slew.
// Expected: both solves converge; the energy optimum is ∫uᵀu dt ≈ 0.9233 N² s; the
// optimized commands replayed open loop through the zero-order model (CVODES) reach the
// target within 1e-4 m and 1e-4 rad; the least time is T* ≈ 2.168 s, between the 1.50 s
// of thrusting straight at 2 N and the 3 s of the energy slew. Exits 1 otherwise.
#include <cmath>
#include <cstdio>
#include <vector>

#include "freeflex/trajopt/replay.hpp"

using namespace freeflex;

int main() {
  const double pi = std::acos(-1.0);
  // NOA only sizes the elastic part, which the zero-order (rigid) model does not use.
  const FlexibleBody body(Beam(BeamProperties::uniform(1.0, 1.0, 1.0)), 2,
                          {{"left", ForceElement::Type::Thruster, 0.0, {0.0, 1.0}, false},
                           {"right", ForceElement::Type::Thruster, 1.0, {0.0, 1.0}, false}});
  ManeuverProblem p;
  p.actuators = {0, 1};
  p.u_min = Eigen::Vector2d(-1.0, -1.0);
  p.u_max = Eigen::Vector2d(1.0, 1.0);
  p.x_final << 1.0, 0.5, pi / 2, 0.0, 0.0, 0.0;  // R [m], theta [rad], then the rates
  p.duration_s = 3.0;
  TrajoptOptions o;
  o.transcription = Transcription::HermiteSimpson;
  o.intervals = 100;
  const TrajoptResult energy = solve_maneuver(body, p, o);
  if (!energy.ok()) {
    std::printf("energy slew failed: %s\n", energy.message.c_str());
    return 1;
  }

  // Replay the commands open loop through CVODES (restarted at every knot).
  IntegratorOptions io;
  io.rtol = 1e-10;
  io.atol = 1e-12;
  const IntegrationResult replay = replay_open_loop(body, p, energy, io);
  if (!replay.ok()) {
    std::printf("replay failed: %s\n", replay.message.c_str());
    return 1;
  }
  const Eigen::VectorXd xT = replay.x.row(replay.x.rows() - 1).transpose();
  const double pos_err = (xT.head<2>() - p.x_final.head<2>()).cwiseAbs().maxCoeff();
  const double ang_err = std::abs(xT(2) - p.x_final(2));

  // The same slew in least time: free duration, time objective.
  ManeuverProblem pt = p;
  pt.free_time = true;
  pt.t_min_s = 0.5;
  pt.t_max_s = 10.0;
  pt.w_energy = 0.0;
  pt.w_time = 1.0;
  const TrajoptResult fastest = solve_maneuver(body, pt, o);

  std::printf("least energy: J = %.5f N^2 s in %d iterations, %.1f ms; replay misses by %.1e m, %.1e rad\n",
              energy.objective, energy.iterations, 1e3 * energy.solve_time_s, pos_err, ang_err);
  std::printf("least time:   %s, T* = %.4f s in %d iterations\n", fastest.ok() ? "converged" : "FAILED",
              fastest.duration_s, fastest.iterations);
  const bool ok = std::abs(energy.objective - 0.9233) < 1e-3 && pos_err < 1e-4 && ang_err < 1e-4 &&
                  fastest.ok() && std::abs(fastest.duration_s - 2.168) < 2e-3;
  std::printf(ok ? "as expected\n" : "NOT as expected\n");
  return ok ? 0 : 1;
}

// Not a benchmark: a probe of one way the perturbation solution might stop following the
// highest elastic mode step by step (issue 19, "cost that grows gently with NOA"). The
// first-order model is linear, x' = A(t) x + g(t), so a Magnus integrator can advance it
// with exact matrix exponentials: the fourth-order two-point Gauss scheme
//   Ω = h/2 (Ã1 + Ã2) + √3 h²/12 [Ã2, Ã1],   [x; 1] ← exp(Ω) [x; 1],
// Ã = [[A, g], [0, 0]] at the Gauss points, fixed steps per piece of the loads. The
// state is first taken to coordinates where the exponential is well scaled: rotated with
// the nominal angle (A then changes only with θ0', θ0''), the rigid coordinates shifted by
// the rigid motion the deformation carries, and q in the body's rest modes with the
// rates divided by ω (docs/theory.md section 8, modal integration variables). The errors
// in θ and q against the perturbation solution at rtol 1e-13 show whether long steps pay:
// they do not (docs/benchmarks.md, "a Magnus probe").
//
//   build/bench/magnus_probe [NOA] [steps per piece...]   (default: 20; 20 40 ... 1280)
//   build/bench/magnus_probe --export NOA DIR   the same coordinates' Ã(t) sampled on 0-1 s
//       and references, for the Python Filon probe of scripts/filon_probe (its README)
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

#include "freeflex/dynamics/first_order.hpp"
#include "freeflex/sim/simulate.hpp"

using namespace freeflex;

namespace {

/// A matrix as raw row-major doubles (numpy.fromfile(...).reshape(rows, cols)).
bool write_matrix(const std::string& path, const Eigen::MatrixXd& M) {
  const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> R = M;
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(R.data()), static_cast<std::streamsize>(sizeof(double) * R.size()));
  return static_cast<bool>(out);
}

}  // namespace

int main(int argc, char** argv) {
  // whole numbers only: "6abc" is refused, not read as 6
  auto whole = [](const char* a) {
    char* end = nullptr;
    const long v = std::strtol(a, &end, 10);
    return end != a && *end == '\0' && v > 0 && v < 1000000 ? static_cast<int>(v) : -1;
  };
  const bool export_mode = argc > 1 && std::string(argv[1]) == "--export";
  if (export_mode && argc != 4) {
    std::fprintf(stderr, "magnus_probe: --export NOA DIR\n");
    return 2;
  }
  const int first_arg = export_mode ? 2 : 1;
  const int noa = argc > first_arg ? whole(argv[first_arg]) : 20;
  std::vector<int> counts;
  for (int i = first_arg + 1; i < argc && !export_mode; ++i) counts.push_back(whole(argv[i]));
  if (counts.empty()) counts = {20, 40, 80, 160, 320, 640, 1280};
  if (noa < 1 || noa > 60) {
    std::fprintf(stderr, "magnus_probe: NOA must be 1..60\n");
    return 2;
  }
  for (int c : counts)
    if (c < 1) {
      std::fprintf(stderr, "magnus_probe: steps per piece must be whole numbers in 1..999999\n");
      return 2;
    }

  // The paper's moment example: +1 N m at the centre for 0.5 s, -1 N m for 0.5 s, then free.
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  const FlexibleBody body(beam, noa, {{"Mz", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false}});
  const Excitation ex{{TimeProfile(TimeProfile::Kind::Steps, {0.0, 0.5, 1.0}, {1.0, -1.0})}};
  SimulationOptions o;
  o.duration_s = 3.0;
  o.output_step_s = 0.5;
  o.integrator.rtol = 1e-13;
  o.integrator.atol = 1e-15;
  const PerturbationResult ref = simulate_perturbation(body, ex, o);
  if (!ref.total.ok()) {
    std::fprintf(stderr, "magnus_probe: the reference failed: %s\n", ref.total.message.c_str());
    return 1;
  }
  const RigidTrajectory& nominal = *ref.nominal;
  const FirstOrderModel first(
      body, nominal, [&ex](const Instant& at, Eigen::Ref<Eigen::VectorXd> c) { c = ex.commands(at); }, {});
  FirstOrderModel::Data data = first.create_data();

  // x = S y: rigid shifted by T q, q = Φ η, q' = Φ diag(ω) ν (and the same for the rates);
  // S⁻¹ from Φᵀ M_c Φ = I, so that no ill-conditioned inverse is formed.
  const int N = body.dofs(), n = 2 * N, ne = N - 3;
  const RestModes rm = rest_modes(body);
  const Eigen::VectorXd omega = rm.omega2.cwiseSqrt();
  const Eigen::MatrixXd Phi_inv = rm.Phi.transpose() * rm.M_c;
  Eigen::MatrixXd S = Eigen::MatrixXd::Identity(n + 1, n + 1), S_inv = S;
  S.block(3, 3, ne, ne) = rm.Phi;
  S.block(0, 3, 3, ne) = -rm.T * rm.Phi;
  S.block(N + 3, N + 3, ne, ne) = rm.Phi * omega.asDiagonal();
  S.block(N, N + 3, 3, ne) = -rm.T * rm.Phi * omega.asDiagonal();
  S_inv.block(3, 3, ne, ne) = Phi_inv;
  S_inv.block(0, 3, 3, ne) = rm.T;
  S_inv.block(N + 3, N + 3, ne, ne) = omega.cwiseInverse().asDiagonal() * Phi_inv;
  S_inv.block(N, N + 3, 3, ne) = rm.T;

  // rotation of R1 and its rate by the nominal angle; with θ0' its derivative term
  auto rotation = [&](double angle, double rate, Eigen::MatrixXd& Rot, Eigen::MatrixXd& Rdot) {
    Rot.setIdentity(n + 1, n + 1);
    Rdot.setZero(n + 1, n + 1);
    const double c = std::cos(angle), s = std::sin(angle);
    for (int i : {0, N}) {
      Rot.block(i, i, 2, 2) << c, -s, s, c;
      Rdot.block(i, i, 2, 2) << 0.0, -rate, rate, 0.0;  // Rotᵀ Rot'
    }
  };
  // Ã(t) in the scaled, rotating coordinates y
  auto augmented = [&](double t, double piece_mid, Eigen::MatrixXd& M) {
    const Instant at{t, piece_mid};
    const StateSpace& ss = first.state_space(data, at);
    M.setZero(n + 1, n + 1);
    M.topLeftCorner(n, n) = ss.A;
    M.topRightCorner(n, 1) = ss.g;
    const RigidState st = nominal.at(at);
    Eigen::MatrixXd Rot, Rdot;
    rotation(st.pos(2), st.vel(2), Rot, Rdot);
    M = S_inv * (Rot.transpose() * M * Rot - Rdot) * S;
  };

  if (export_mode) {
    // DIR/meta.txt: N, 2N, ω of each mode; S.bin, Sinv.bin ((2N+1) x (2N+1)): x = S y;
    // samples_p{0,1}.bin: 501 rows per piece of the loads, t, θ0, θ0', θ0'', command, then
    // Ã(t) row-major in y; ref_{13,14}.bin: the perturbation solution at rtol 1e-13 and
    // 1e-14 every 5 ms on 0-1 s, rows t, total z, total z', zero-order z, zero-order z'.
    const std::string dir = argv[3];
    bool ok = write_matrix(dir + "/S.bin", S) && write_matrix(dir + "/Sinv.bin", S_inv);
    std::ofstream meta(dir + "/meta.txt");
    meta.precision(17);
    meta << N << ' ' << n;
    for (int i = 0; i < ne; ++i) meta << ' ' << omega(i);
    meta << '\n';
    ok = ok && static_cast<bool>(meta);
    const int K = 501;
    Eigen::MatrixXd M;
    for (int p = 0; p < 2 && ok; ++p) {
      const double a = 0.5 * p, b = a + 0.5, mid = 0.5 * (a + b);
      Eigen::MatrixXd rows(K, 5 + (n + 1) * (n + 1));
      for (int k = 0; k < K; ++k) {
        const double t = a + (b - a) * k / (K - 1);
        augmented(t, mid, M);
        const RigidState st = nominal.at(Instant{t, mid});
        rows(k, 0) = t;
        rows(k, 1) = st.pos(2);
        rows(k, 2) = st.vel(2);
        rows(k, 3) = st.acc(2);
        rows(k, 4) = ex.commands(Instant{t, mid})(0);
        const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Mr = M;
        rows.row(k).tail(Mr.size()) = Eigen::Map<const Eigen::RowVectorXd>(Mr.data(), Mr.size());
      }
      ok = write_matrix(dir + "/samples_p" + std::to_string(p) + ".bin", rows);
    }
    for (int k : {13, 14}) {
      if (!ok) break;
      SimulationOptions r = o;
      r.duration_s = 1.0;
      r.output_step_s = 0.005;
      r.integrator.rtol = std::pow(10.0, -k);
      r.integrator.atol = 1e-2 * r.integrator.rtol;
      const PerturbationResult sol = simulate_perturbation(body, ex, r);
      if (!sol.total.ok()) {
        std::fprintf(stderr, "magnus_probe: the reference at rtol 1e-%d failed: %s\n", k, sol.total.message.c_str());
        return 1;
      }
      const Eigen::Index T = sol.total.t.size();
      Eigen::MatrixXd R(T, 1 + 4 * N);
      R << sol.total.t, sol.total.z, sol.total.z_dot, sol.zero_order.z, sol.zero_order.z_dot;
      ok = write_matrix(dir + "/ref_" + std::to_string(k) + ".bin", R);
    }
    if (!ok) {
      std::fprintf(stderr, "magnus_probe: cannot write into %s (does it exist?)\n", dir.c_str());
      return 3;
    }
    std::printf("NOA %d: exported to %s (omega_max %.1f rad/s)\n", noa, dir.c_str(), omega.maxCoeff());
    return 0;
  }

  std::printf("NOA %d, omega_max %.0f rad/s; errors against the perturbation solution at rtol 1e-13\n\n", noa,
              omega.maxCoeff());
  std::printf("| steps a piece | h omega_max (0-1 s) | error theta at 1 s | at 3 s | error q at 3 s | exponentials | wall [ms] |\n");
  std::printf("| --- | --- | --- | --- | --- | --- | --- |\n");
  const double ends[] = {0.0, 0.5, 1.0, 3.0};
  const double c1 = 0.5 - std::sqrt(3.0) / 6.0, c2 = 0.5 + std::sqrt(3.0) / 6.0;
  for (int per_piece : counts) {
    const auto start = std::chrono::steady_clock::now();
    Eigen::VectorXd y = Eigen::VectorXd::Zero(n + 1);
    y[n] = 1.0;
    Eigen::MatrixXd A1, A2, Omega;
    double err_theta[4] = {0, 0, 0, 0}, err_q = 0.0;
    long exponentials = 0;
    for (int p = 0; p < 3; ++p) {
      const double a = ends[p], b = ends[p + 1], mid = 0.5 * (a + b), h = (b - a) / per_piece;
      for (int k = 0; k < per_piece; ++k) {
        const double t = a + k * h;
        augmented(t + c1 * h, mid, A1);
        augmented(t + c2 * h, mid, A2);
        Omega = 0.5 * h * (A1 + A2) + (std::sqrt(3.0) * h * h / 12.0) * (A2 * A1 - A1 * A2);
        y = Eigen::MatrixXd(Omega.exp()) * y;
        ++exponentials;
      }
      // back to x at the piece's end and against the reference's output there
      Eigen::VectorXd x = S * y;
      const RigidState st = nominal.at(Instant{b, mid});
      const double c = std::cos(st.pos(2)), s = std::sin(st.pos(2));
      for (int i : {0, N}) {
        const Eigen::Vector2d v = x.segment<2>(i);
        x(i) = c * v(0) - s * v(1);
        x(i + 1) = s * v(0) + c * v(1);
      }
      int row = -1;
      for (int i = 0; i < ref.total.t.size(); ++i)
        if (std::abs(ref.total.t[i] - b) < 1e-12) row = i;
      if (row < 0) {
        std::fprintf(stderr, "magnus_probe: the reference has no output at t = %g s\n", b);
        return 1;
      }
      err_theta[p + 1] = std::abs(x[2] + ref.zero_order.z(row, 2) - ref.total.z(row, 2));
      if (p == 2) err_q = (x.segment(3, ne) - ref.total.z.row(row).segment(3, ne).transpose()).cwiseAbs().maxCoeff();
    }
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    std::printf("| %d | %.3g | %.2e | %.2e | %.2e | %ld | %.0f |\n", per_piece, 0.5 / per_piece * omega.maxCoeff(),
                err_theta[2], err_theta[3], err_q, exponentials, ms);
  }
  return 0;
}

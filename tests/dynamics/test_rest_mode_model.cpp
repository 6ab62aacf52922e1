// The full model in rest-mode coordinates (src/dynamics/rest_mode_model.hpp) against the
// full model in physical coordinates: the same equations, other arithmetic.
#include <catch2/catch.hpp>

#include <random>

#include "dynamics/rest_mode_model.hpp"
#include "freeflex/dynamics/full_model.hpp"
#include "support/bodies.hpp"

using namespace freeflex;

namespace {
FlexibleBody rich_body(int noa, std::vector<double> damping = {}, bool stiffening = false) {
  return FlexibleBody(Beam(freeflex_test::rich_beam()), noa, freeflex_test::rich_elements(), std::move(damping),
                      stiffening);
}
}  // namespace

TEST_CASE("rest-mode coordinates: the map is one to one and the derivatives are the full model's", "[dynamics]") {
  // The rich beam (o off the mass centre, hub, tip mass, two segments), damped, with all four
  // element types commanded at once, at random states with large rates and deflections.
  // y' mapped back must equal x' of FullModel::rhs at x = map(y): the map is constant and
  // linear, so it carries derivatives as it carries states.
  // Every mode damped (n = 7: modes 5-7 in the kernel's scalar remainder), and the damping
  // applied both by its diagonal and as the full matrix (the fallback for modes of one
  // frequency, forced here).
  for (int n : {4, 7, 20})
  for (bool stiffening : {false, true})
  for (bool dense_damping : {false, true}) {
    std::vector<double> ratios(n);
    for (int k = 0; k < n; ++k) ratios[k] = 0.01 + 0.005 * (k % 3);
    const FlexibleBody body = rich_body(n, ratios, stiffening);
    const FullModel physical(body);
    const detail::RestModeModel rest(body, dense_damping);
    FullModel::Data dp = physical.create_data();
    detail::RestModeModel::Data dr = rest.create_data();
    const int N = body.dofs();
    std::mt19937 gen(11 + n);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    double worst = 0.0, worst_map = 0.0;
    int compared = 0;
    for (int trial = 0; trial < 100; ++trial) {
      Eigen::VectorXd x(2 * N), u(body.elements().size());
      for (int i = 0; i < 2 * N; ++i) x(i) = U(gen) * (i < 3 || (i >= N && i < N + 3) ? 3.0 : 0.05);
      for (int e = 0; e < u.size(); ++e) u(e) = U(gen);
      const Eigen::VectorXd y = rest.to_rest_modes(x);
      Eigen::VectorXd back(2 * N), yd_phys(2 * N);
      rest.to_physical(y, back);
      worst_map = std::max(worst_map, (back - x).cwiseAbs().maxCoeff() / x.cwiseAbs().maxCoeff());
      // the stiffened model leaves its range where 𝕄_b(q) has lost most of its determinant
      // at rest (FullModel::rhs): both coordinates must say so at the same states
      const bool in_range = physical.rhs(dp, x, u);
      CHECK(rest.rhs(dr, y, u) == in_range);
      if (!in_range) continue;
      ++compared;
      rest.to_physical(dr.x_dot, yd_phys);
      worst = std::max(worst, (yd_phys - dp.x_dot).cwiseAbs().maxCoeff() / dp.x_dot.cwiseAbs().maxCoeff());
    }
    INFO("n = " << n << ", geometric stiffening " << stiffening << ", dense damping " << dense_damping << ": map "
                 << worst_map << ", derivatives " << worst
                 << " (" << compared << " states in range)");
    // Ψ comes from a generalized eigensolver, so the block inverse and Ψᵀ K Ψ = Λ hold to
    // round-off: seen 2e-16 for the map and 3e-15 to 8e-15 for the derivatives (n = 4-20,
    // with and without stiffening)
    CHECK(compared >= 50);  // most random states are in range
    CHECK(worst_map < 1e-14);
    // stiffened: the 4 x 4 Woodbury core near its determinant limit (1e-3) magnifies the
    // round-off, seen up to 1.8e-13 here and 6.7e-13 over 2 000 random states
    CHECK(worst < (stiffening ? 5e-12 : 1e-13));
  }
}

TEST_CASE("rest-mode coordinates: the generalized force and damping carry the same power", "[dynamics]") {
  const FlexibleBody body = rich_body(6, {0.05, 0.02}, GENERATE(false, true));
  const detail::RestModeModel rest(body);
  const int N = body.dofs();
  std::mt19937 gen(3);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd x(2 * N), u(body.elements().size());
    for (int i = 0; i < 2 * N; ++i) x(i) = U(gen) * (i < 3 || (i >= N && i < N + 3) ? 2.0 : 0.05);
    for (int e = 0; e < u.size(); ++e) u(e) = U(gen);
    const Eigen::VectorXd y = rest.to_rest_modes(x);
    const Eigen::VectorXd G = body.generalized_force(x(2), x.segment(3, N - 3), u);
    Eigen::VectorXd Gy(N);
    rest.generalized_force(y(2), y.segment(3, N - 3), u, Gy);
    const auto zd = x.tail(N);
    const auto yd = y.tail(N);
    const double power = zd.dot(G), damping = zd.dot(body.damping() * zd);
    CHECK(yd.dot(Gy) == Approx(power).margin(1e-12));  // round-off of sums of O(1) terms
    CHECK(yd.dot(rest.damping() * yd) == Approx(damping).margin(1e-12));
    CHECK(rest.damping_power(yd) == Approx(damping).margin(1e-12));  // by the diagonal
  }
}

// The finite-element basis (docs/theory.md section 2b) against the exact frequencies of
// tests/reference/ (transfer matrices and power series in mpmath, scripts/reference/):
// stepped, stepped with hub and tip mass, tapered, uniform; convergence orders h^4 and
// h^8; the hybrid model reproducing the element model; the modes clamped at o (the
// paper's functions on the uniform beam); the mesh; bad input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>

#include "freeflex/analysis/free_vibration.hpp"
#include "freeflex/model/finite_element_basis.hpp"
#include "freeflex/model/modal_integrals.hpp"
#include "support/reference_csv.hpp"

using namespace freeflex;
using freeflex_test::reference_column;

namespace {

/// Relative errors of the hybrid model's first five elastic frequencies.
Eigen::VectorXd errors(const Beam& beam, FiniteElementOptions o, const Eigen::VectorXd& exact) {
  const FiniteElementBasis basis(beam, 6, o);
  const Eigen::VectorXd omega = free_vibration(modal_integrals(beam, basis)).omega.head(5);
  return omega.cwiseQuotient(exact).array() - 1.0;
}

}  // namespace

TEST_CASE("FE basis: stepped beam, bare and with hub and tip mass, five frequencies to 1e-10", "[model]") {
  for (const bool payloads : {false, true}) {
    const Beam beam(freeflex_test::stepped_beam(payloads));
    const Eigen::VectorXd exact =
        reference_column("stepped_beam_frequencies.csv", payloads ? "stepped_hub_tip" : "stepped_bare");
    const FiniteElementBasis basis(beam, 6, {40, 5});
    const Eigen::VectorXd omega = free_vibration(modal_integrals(beam, basis)).omega.head(5);
    const Eigen::VectorXd err = omega.cwiseQuotient(exact).array() - 1.0;
    INFO(std::setprecision(3) << "payloads " << payloads << ", relative errors " << err.transpose());
    // 40 quintic elements: measured <= 2.5e-11 (bare, mode 5) and 1.0e-11 (payloads, mode 5);
    // issue 15 asks 1e-8 with at most 200 elements
    CHECK(err.cwiseAbs().maxCoeff() <= 1e-10);
    // a conforming Ritz space: never below the exact value (round-off of 1e-14 allowed)
    CHECK(err.minCoeff() >= -1e-13);
    // the element model itself, whose eigenvalues the hybrid reproduces (below)
    const Eigen::VectorXd fe_err = basis.element_model_omega().head(5).cwiseQuotient(exact).array() - 1.0;
    CHECK(fe_err.cwiseAbs().maxCoeff() <= 1e-10);
  }
}

TEST_CASE("FE basis: cubic elements converge as h^4, quintic ones as h^8", "[model]") {
  // Meshes that nest exactly: stepped_bare's key intervals (0.425, 0.175, 0.4 m) take
  // multiples of 40 elements, stepped_hub_tip's (0.5, 0.1, 0.4 m) multiples of 10.
  const Beam bare(freeflex_test::stepped_beam(false)), hub(freeflex_test::stepped_beam(true));
  const Eigen::VectorXd exact_bare = reference_column("stepped_beam_frequencies.csv", "stepped_bare");
  const Eigen::VectorXd exact_hub = reference_column("stepped_beam_frequencies.csv", "stepped_hub_tip");
  struct Case {
    const Beam* beam;
    const Eigen::VectorXd* exact;
    int order, coarse;
    double lo, hi;
  };
  // observed orders log2(err(N) / err(2N)): cubic 3.98 .. 4.00, quintic 7.86 .. 8.01
  const Case cases[] = {{&bare, &exact_bare, 3, 40, 3.9, 4.1},
                        {&hub, &exact_hub, 3, 20, 3.9, 4.1},
                        {&hub, &exact_hub, 5, 10, 7.7, 8.2}};
  for (const Case& c : cases) {
    const Eigen::VectorXd e1 = errors(*c.beam, {c.coarse, c.order}, *c.exact);
    const Eigen::VectorXd e2 = errors(*c.beam, {2 * c.coarse, c.order}, *c.exact);
    for (int k = 0; k < 5; ++k) {
      if (e2(k) < 1e-12) continue;  // at round-off (quintic mode 1 at 20 elements: 5e-14)
      const double rate = std::log2(e1(k) / e2(k));
      INFO("order " << c.order << ", " << c.coarse << " -> " << 2 * c.coarse << " elements, mode " << k + 1
                    << ": errors " << e1(k) << " -> " << e2(k) << ", observed order " << rate);
      CHECK(rate >= c.lo);
      CHECK(rate <= c.hi);
    }
  }
}

TEST_CASE("FE basis: the hybrid model reproduces the element model's frequencies", "[model]") {
  const Beam beam(freeflex_test::stepped_beam(true));
  for (const int order : {3, 5}) {
    const FiniteElementBasis basis(beam, 8, {30, order});
    const ModalIntegrals mi = modal_integrals(beam, basis);
    const Eigen::VectorXd omega = free_vibration(mi).omega;
    const double diff = (omega.cwiseQuotient(basis.element_model_omega()).array() - 1.0).abs().maxCoeff();
    INFO("order " << order << ": max relative difference " << diff);
    // rigid modes and phi_1..phi_n span the element model's rigid and first n modes: equal
    // up to the round-off of both eigensolvers (measured <= 3e-14)
    CHECK(diff <= 1e-12);
    // The modes are mass- and stiffness-orthogonal: with the rigid momenta held the elastic
    // mass is m I (eq. 6.8), and K = m diag(omega^2) (curvature ignores the rigid part).
    const Eigen::MatrixXd M0 = rest_mass_matrix(mi);
    const int n = mi.size();
    const Eigen::MatrixXd Mc =
        mi.M - M0.block(3, 0, n, 3) * M0.topLeftCorner<3, 3>().ldlt().solve(M0.block(0, 3, 3, n));
    const Eigen::MatrixXd Kexp = mi.m * Eigen::VectorXd(omega.cwiseAbs2()).asDiagonal();
    // quadrature and eigenvector round-off (measured 2e-15 and 4e-14 relative)
    CHECK((Mc - mi.m * Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff() <= 1e-12 * mi.m);
    CHECK((mi.K - Kexp).cwiseAbs().maxCoeff() <= 1e-12 * Kexp.maxCoeff());
  }
}

TEST_CASE("FE basis: uniform beam gives the exact free-free roots (Table 1's exact row)", "[model]") {
  const Eigen::VectorXd lambda_exact = reference_column("stepped_beam_frequencies.csv", "uniform", "lambda");
  for (const double s_o : {0.5, 0.3, 0.001}) {  // o anywhere: a bare beam's frequencies do not depend on it
    BeamProperties p = BeamProperties::uniform(1.0, 1.0, 1.0);
    p.reference_m = s_o;
    const Beam beam(p);
    const FiniteElementBasis basis(beam, 6, {40, 5});
    const Eigen::VectorXd omega = free_vibration(modal_integrals(beam, basis)).omega;
    for (int k = 0; k < 5; ++k) {
      const double lambda = paper_lambda(omega(k), 1.0, 1.0, 1.0);
      INFO("o at " << s_o << ", mode " << k + 1 << ": lambda " << std::setprecision(16) << lambda);
      // measured <= 1.5e-11 (mode 5; lambda's error is half omega's)
      CHECK(std::abs(lambda / lambda_exact(k) - 1.0) <= 1e-10);
    }
  }
}

TEST_CASE("FE basis: tapered beam, bare and with tip mass, to 1e-6 with cubics and 1e-10 with quintics",
          "[model]") {
  for (const bool tip : {false, true}) {
    const Beam beam(freeflex_test::tapered_beam(tip));
    const Eigen::VectorXd exact = reference_column("tapered_beam_frequencies.csv", tip ? "tapered_tip" : "tapered_bare");
    const Eigen::VectorXd e5 = errors(beam, {40, 5}, exact);
    const Eigen::VectorXd e3 = errors(beam, {160, 3}, exact);
    INFO("tip " << tip << ": quintic(40) " << e5.transpose() << "; cubic(160) " << e3.transpose());
    CHECK(e5.cwiseAbs().maxCoeff() <= 1e-10);  // measured 2.8e-11 (bare) and 1.8e-11 (tip), mode 5
    CHECK(e3.cwiseAbs().maxCoeff() <= 1e-6);   // measured 9.4e-8 (bare, mode 5); issue 15 asks 1e-6
    CHECK(std::min(e5.minCoeff(), e3.minCoeff()) >= -1e-13);  // upper bounds, up to round-off
  }
}

TEST_CASE("FE basis clamped at o: uniform beam, o at the centre: cantilever pairs, the paper's Ritz values",
          "[model]") {
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  FiniteElementOptions o{80, 5};
  o.modes = FiniteElementOptions::Modes::ClampedAtReference;
  const FiniteElementBasis basis(beam, 10, o);
  for (int k = 0; k < 10; ++k) {
    // each half a cantilever of length 0.5 (closed form: eq. 2.2), once on each side
    const double beta = cantilever_root(k / 2 + 1) / 0.5;
    INFO("mode " << k + 1 << ": " << std::setprecision(16) << basis.element_model_omega()(k));
    // 40 quintic elements per half: error falling as h^8, measured 4.8e-12 (mode 10; 20
    // elements per half: 1.2e-9)
    CHECK(std::abs(basis.element_model_omega()(k) / (beta * beta) - 1.0) <= 1e-10);
  }
  // one-sided, the left first on a tie (equal halves)
  CHECK(basis.evaluate(-0.3).phi(0) != 0.0);
  CHECK(basis.evaluate(0.3).phi(0) == 0.0);
  CHECK(basis.evaluate(0.3).phi(1) != 0.0);
  CHECK(basis.evaluate(-0.3).phi(1) == 0.0);
  // At even n the two spaces are the same (sums and differences of a pair are the paper's
  // symmetric and antisymmetric functions): the hybrid frequencies are the paper basis's
  // Rayleigh-Ritz values (Table 1's NOA rows), not the exact free-free roots.
  for (const int n : {2, 4, 6, 8, 10}) {
    const Eigen::VectorXd fe = free_vibration(modal_integrals(beam, FiniteElementBasis(beam, n, o))).omega;
    const Eigen::VectorXd paper = free_vibration(modal_integrals(beam, AdmissibleBasis(n, 0.5, 0.5))).omega;
    const double diff = (fe.cwiseQuotient(paper).array() - 1.0).abs().maxCoeff();
    INFO("n = " << n << ": max relative difference " << diff);
    CHECK(diff <= 1e-10);  // the clamped modes' discretization error (measured 1.9e-11 at n = 10)
  }
}

TEST_CASE("FE basis clamped at o: stepped beam with o off-centre: Ritz values above exact, falling with n",
          "[model]") {
  const Beam beam(freeflex_test::stepped_beam(true));
  const Eigen::VectorXd exact = reference_column("stepped_beam_frequencies.csv", "stepped_hub_tip");
  FiniteElementOptions o{40, 5};
  o.modes = FiniteElementOptions::Modes::ClampedAtReference;
  Eigen::VectorXd previous = Eigen::VectorXd::Constant(5, 1.0);
  for (const int n : {6, 12, 24, 48}) {
    const Eigen::VectorXd omega = free_vibration(modal_integrals(beam, FiniteElementBasis(beam, n, o))).omega;
    const Eigen::VectorXd err = omega.head(5).cwiseQuotient(exact).array() - 1.0;
    INFO("n = " << n << ": relative errors " << std::setprecision(3) << err.transpose());
    CHECK(err.minCoeff() >= -1e-13);  // a conforming Ritz space (round-off allowed)
    // nested spaces: never rising (round-off of the eigensolvers allowed)
    CHECK(((err - previous).array() <= 1e-12).all());
    previous = err;
  }
  // the truncation error of n clamped modes, falling as ~n^-5 (the paper's basis: 1/NOA):
  // measured 3.4e-8 (mode 5) at n = 48; 5.6e-5 at n = 12
  CHECK(previous.maxCoeff() <= 1e-7);
}

TEST_CASE("FE basis: Phi and Phi' vanish at o, C1 at nodes, derivatives match central differences",
          "[model]") {
  const Beam beam(freeflex_test::stepped_beam(true));
  for (const int order : {3, 5}) {
    const FiniteElementBasis basis(beam, 6, {12, order});
    const BasisValues o = basis.evaluate(0.0);
    // set to zero at the node of o by construction (eq. 2.6)
    CHECK(o.phi.cwiseAbs().maxCoeff() == 0.0);
    CHECK(o.dphi.cwiseAbs().maxCoeff() == 0.0);
    const std::vector<double>& x = basis.nodes();
    const double scale = basis.evaluate(x.back()).phi.cwiseAbs().maxCoeff();
    for (std::size_t i = 1; i + 1 < x.size(); ++i) {
      const double h = 1e-9 * (x[i + 1] - x[i - 1]);
      const BasisValues l = basis.evaluate(x[i] - h), r = basis.evaluate(x[i]);
      // value and slope continuous across the node: differences O(h * slope), O(h * curvature)
      CHECK((l.phi - r.phi).cwiseAbs().maxCoeff() <= 1e-6 * scale);
      CHECK((l.dphi - r.dphi).cwiseAbs().maxCoeff() <= 1e-6 * r.ddphi.cwiseAbs().maxCoeff() + 1e-9 * scale);
    }
    for (std::size_t i = 0; i + 1 < x.size(); ++i) {
      const double xm = x[i] + 0.37 * (x[i + 1] - x[i]), h = 1e-5 * (x[i + 1] - x[i]);
      const BasisValues v = basis.evaluate(xm), p = basis.evaluate(xm + h), m = basis.evaluate(xm - h);
      const Eigen::RowVectorXd d1 = (p.phi - m.phi) / (2 * h), d2 = (p.dphi - m.dphi) / (2 * h);
      // central differences of a polynomial: O(h^2 phi''') plus round-off eps*phi/h (~1e-9 relative)
      CHECK((d1 - v.dphi).cwiseAbs().maxCoeff() <= 1e-7 * v.dphi.cwiseAbs().maxCoeff() + 1e-7 * scale);
      CHECK((d2 - v.ddphi).cwiseAbs().maxCoeff() <= 1e-7 * v.ddphi.cwiseAbs().maxCoeff() + 1e-7 * scale);
    }
  }
}

TEST_CASE("FE basis: mesh has nodes at the ends, o, junctions and point masses", "[model]") {
  BeamProperties p = freeflex_test::stepped_beam(true);
  p.point_masses.push_back({0.8, 0.05});
  p.point_masses.push_back({0.6 + 1e-6, 0.05});  // 1e-6 m from the junction: lumped on its node
  const Beam beam(p);
  const FiniteElementBasis basis(beam, 4, {25, 5});
  const std::vector<double>& x = basis.nodes();
  CHECK(basis.elements() == 25);
  CHECK(static_cast<int>(x.size()) == 26);
  CHECK(x.front() == beam.x_left());
  CHECK(x.back() == beam.x_right());
  CHECK(basis.dofs() == 2 * 26 + 2 * 25);  // (w, w') per node, two bubbles per element
  auto has = [&](double s) {
    return std::any_of(x.begin(), x.end(), [&](double n) { return std::abs(n - beam.x_of(s)) <= 1e-15; });
  };
  CHECK(std::find(x.begin(), x.end(), 0.0) != x.end());  // o exactly
  CHECK(has(0.6));                                       // junction (up to one rounding of x = s - s_o)
  CHECK(has(0.8));
  CHECK_FALSE(has(0.6 + 1e-6));
  // the longest element as short as 25 elements allow over key intervals 0.5, 0.1, 0.2, 0.2
  double longest = 0.0;
  for (std::size_t i = 0; i + 1 < x.size(); ++i) longest = std::max(longest, x[i + 1] - x[i]);
  CHECK(longest == Approx(0.5 / 12).epsilon(1e-12));  // 12 + 3 + 5 + 5 elements
  // fewer elements than key intervals: one per interval
  CHECK(FiniteElementBasis(beam, 4, {1, 3}).elements() == 4);
}

TEST_CASE("FE basis: bad options and mode counts are rejected with their values", "[model]") {
  const Beam beam(freeflex_test::stepped_beam(false));
  CHECK_THROWS_WITH(FiniteElementBasis(beam, 4, {0, 5}), Catch::Contains("elements = 0, must be in [1, 2000]"));
  CHECK_THROWS_WITH(FiniteElementBasis(beam, 4, {2001, 5}), Catch::Contains("elements = 2001"));
  CHECK_THROWS_WITH(FiniteElementBasis(beam, 4, {10, 4}), Catch::Contains("element_order = 4, must be 3 or 5"));
  CHECK_THROWS_WITH(FiniteElementBasis(beam, 0, {10, 3}), Catch::Contains("0 modes requested, must be in [1, 20]"));
  // 10 cubic elements: 22 DOFs, two of them rigid
  CHECK_THROWS_WITH(FiniteElementBasis(beam, 21, {10, 3}), Catch::Contains("must be in [1, 20]"));
  CHECK(FiniteElementBasis(beam, 20, {10, 3}).size() == 20);
}

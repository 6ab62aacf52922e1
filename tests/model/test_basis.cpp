// Admissible functions (docs/theory.md section 2): roots, cancellation-free evaluation,
// tip values and orthogonality up to NOA = 60, derivatives against finite differences.
#include <catch2/catch.hpp>

#include <cmath>

#include "freeflex/model/basis.hpp"
#include "freeflex/model/quadrature.hpp"

using namespace freeflex;

TEST_CASE("cantilever roots solve 1 + cos(l) cosh(l) = 0", "[model]") {
  // Reference digits: the spec's list of the first six roots.
  const double ref[6] = {1.875104068711961, 4.694091132974175, 7.854757438237613,
                         10.99554073487547, 14.13716839104647, 17.27875953208824};
  // the root finder converges to round-off; the reference has 16 digits
  for (int k = 1; k <= 6; ++k) CHECK(cantilever_root(k) == Approx(ref[k - 1]).epsilon(1e-14));
  for (int k = 1; k <= 50; ++k) {
    const double l = cantilever_root(k);
    // cos l = -1/cosh l; residual relative to the O(1) terms, near machine precision
    CHECK(std::abs(std::cos(l) + 1.0 / std::cosh(l)) < 1e-13);
    // the roots approach (2k - 1) pi / 2; the widest gap is the first, 1.8751 - pi/2 = 0.3043
    CHECK(std::abs(l - (2 * k - 1) * M_PI / 2) < 0.31);
  }
}

TEST_CASE("cantilever modes: tip value +-2 and orthogonality up to NOA = 60", "[model]") {
  const int kmax = 30;  // NOA = 60 uses cantilever modes 1..30 on each half
  const double a = 0.5;
  for (int k = 1; k <= kmax; ++k) {
    const CantileverConstants c(k);
    const CantileverMode tip = c.at(c.lambda);
    // Textbook form gives 0 here from k ~ 12; the scaled form keeps all digits, so
    // round-off of O(1) terms (measured 4e-16) is the tolerance.
    CHECK(std::abs(std::abs(tip.value) - 2.0) < 1e-13);
    CHECK(tip.value * (k % 2 == 1 ? 1.0 : -1.0) > 0.0);  // sign alternates: (-1)^(k+1) 2
    const CantileverMode root = c.at(0.0);
    // clamped: psi(0) = psi'(0) = 0, up to round-off of O(1) terms
    CHECK(std::abs(root.value) < 1e-13);
    CHECK(std::abs(root.d1) < 1e-13);
    // free end: no moment; psi'' is of order lambda^2, so round-off relative to that (measured 4e-15)
    CHECK(std::abs(tip.d2) < 1e-13 * c.lambda * c.lambda);
  }
  // Integral of psi_i psi_j over [0, a] = a delta_ij, composite Gauss with panels that
  // resolve wavenumber 2 * lambda_30 / a (relative tolerance 1e-10 from the issue).
  const GaussRule g = composite_gauss(0.0, a, 200, 20);
  std::vector<CantileverConstants> modes;
  for (int k = 1; k <= kmax; ++k) modes.emplace_back(k);
  Eigen::MatrixXd vals(g.nodes.size(), kmax);
  for (int i = 0; i < g.nodes.size(); ++i)
    for (int k = 0; k < kmax; ++k) vals(i, k) = modes[k].at(modes[k].lambda * g.nodes(i) / a).value;
  const Eigen::MatrixXd G = vals.transpose() * g.weights.asDiagonal() * vals;
  const double err = (G - a * Eigen::MatrixXd::Identity(kmax, kmax)).cwiseAbs().maxCoeff() / a;
  INFO("max deviation of the Gram matrix from a I, relative: " << err);
  CHECK(err < 1e-10);
}

TEST_CASE("basis symmetry and derivatives match central differences", "[model]") {
  const AdmissibleBasis b(12, 0.5, 0.5);
  for (double x : {0.05, 0.17, 0.31, 0.49}) {
    const BasisValues r = b.evaluate(x), l = b.evaluate(-x);
    for (int j = 0; j < 12; ++j) {
      const double s = (j % 2 == 0) ? 1.0 : -1.0;  // odd-numbered symmetric, even antisymmetric
      CHECK(l.phi(j) == Approx(s * r.phi(j)).margin(1e-13));  // mirror images: round-off of O(1) values
    }
  }
  const AdmissibleBasis u(10, 0.3, 0.7);  // unequal halves: o off the centre
  const double h = 1e-5;
  for (double x : {-0.29, -0.12, -0.01, 0.02, 0.33, 0.69}) {
    const BasisValues v = u.evaluate(x), p = u.evaluate(x + h), m = u.evaluate(x - h);
    const Eigen::RowVectorXd d1 = (p.phi - m.phi) / (2 * h);
    const Eigen::RowVectorXd d2 = (p.dphi - m.dphi) / (2 * h);
    // central differences: O(h^2 |phi'''|) ~ 1e-10 * beta^3 with beta <= 30 -> 1e-5 relative
    CHECK((d1 - v.dphi).cwiseAbs().maxCoeff() < 1e-5 * v.dphi.cwiseAbs().maxCoeff());
    CHECK((d2 - v.ddphi).cwiseAbs().maxCoeff() < 1e-5 * v.ddphi.cwiseAbs().maxCoeff());
  }
  // at o every function and its slope vanish, up to round-off of O(1) values (phi, measured
  // 2e-16) and of O(beta) values (phi' = psi'/a on the 0.3 half, beta <= 47; measured 1.5e-15)
  const BasisValues o = u.evaluate(0.0);
  CHECK(o.phi.cwiseAbs().maxCoeff() < 1e-13);
  CHECK(o.dphi.cwiseAbs().maxCoeff() < 1e-12);
}

TEST_CASE("basis rejects bad sizes", "[model]") {
  CHECK_THROWS_WITH(AdmissibleBasis(0, 0.5, 0.5), Catch::Contains("noa = 0, must be in [1, 100]"));
  CHECK_THROWS_WITH(AdmissibleBasis(kMaxNoa + 1, 0.5, 0.5), Catch::Contains("must be in [1, 100]"));
  CHECK_THROWS_AS(AdmissibleBasis(4, 0.0, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(AdmissibleBasis(4, -0.1, 0.5), std::invalid_argument);
}

TEST_CASE("o at an end: the other side's cantilever modes in order", "[model]") {
  // a_left = 0: function k is the k-th cantilever mode on [0, a_right]; nothing left of o
  const double a = 0.8;
  const AdmissibleBasis right(7, 0.0, a), left(7, a, 0.0);
  REQUIRE(right.one_sided());
  CHECK(right.max_wavenumber() == Approx(cantilever_root(7) / a).epsilon(1e-15));  // one division
  for (double xi : {0.13, 0.4, 0.8}) {
    const BasisValues r = right.evaluate(xi), l = left.evaluate(-xi);
    for (int k = 1; k <= 7; ++k) {
      const CantileverConstants c(k);
      const double beta = c.lambda / a;
      const CantileverMode m = c.at(beta * xi);
      // the same formula evaluated once more: bit-equal values, slopes mirrored
      CHECK(r.phi(k - 1) == m.value);
      CHECK(r.dphi(k - 1) == beta * m.d1);
      CHECK(l.phi(k - 1) == m.value);
      CHECK(l.dphi(k - 1) == -(beta * m.d1));
    }
  }
  // at o: clamped (round-off of O(1) values, measured 2e-16; slopes O(beta) with beta <= 25)
  CHECK(right.evaluate(0.0).phi.cwiseAbs().maxCoeff() < 1e-13);
  CHECK(right.evaluate(0.0).dphi.cwiseAbs().maxCoeff() < 1e-12);
  // the side without beam: zero
  CHECK(right.evaluate(-0.1).phi.cwiseAbs().maxCoeff() == 0.0);
  CHECK(left.evaluate(0.1).dphi.cwiseAbs().maxCoeff() == 0.0);
}

TEST_CASE("Gauss-Legendre integrates polynomials of degree 2n-1 exactly", "[model]") {
  for (int n : {1, 2, 5, 20}) {
    const GaussRule g = gauss_legendre(n);
    for (int p = 0; p <= 2 * n - 1; ++p) {
      const double exact = (p % 2 == 1) ? 0.0 : 2.0 / (p + 1);
      double sum = 0.0;
      for (int i = 0; i < n; ++i) sum += g.weights(i) * std::pow(g.nodes(i), p);
      CHECK(sum == Approx(exact).margin(1e-14));  // round-off of n terms
    }
  }
}

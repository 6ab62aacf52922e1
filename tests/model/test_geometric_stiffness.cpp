// Geometric stiffening integrals (docs/theory.md section 14): H(x), H_bar and G_c against
// their definitions integrated another way (nested quadrature of a different order),
// the classical centrifugal tension of a cantilever, and their symmetries.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "freeflex/model/modal_integrals.hpp"
#include "support/bodies.hpp"
#include "support/reference_csv.hpp"

using namespace freeflex;

namespace {

/// ∫_a^b f by composite 12-point Gauss on `panels` panels (not the library's 20-point rule).
template <class F>
Eigen::MatrixXd integrate(double a, double b, int panels, int n, F f) {
  const GaussRule g = gauss_legendre(12);
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(n, n);
  const double h = (b - a) / panels;
  for (int p = 0; p < panels; ++p)
    for (int i = 0; i < g.nodes.size(); ++i) {
      const double x = a + h * (p + 0.5 * (g.nodes(i) + 1.0));
      sum += 0.5 * h * g.weights(i) * f(x);
    }
  return sum;
}

double rel(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

}  // namespace

TEST_CASE("H(x): its derivative is Phi'^T Phi', zero at o, positive semidefinite", "[model]") {
  const Beam beam(freeflex_test::rich_beam());
  const AdmissibleBasis basis = make_basis(beam, 8);
  CHECK(foreshortening_matrix(beam, basis, 0.0).cwiseAbs().maxCoeff() == 0.0);
  for (double x : {-0.41, -0.2, 0.13, 0.35, 0.61}) {
    const double h = 1e-5;
    const Eigen::MatrixXd dH =
        (foreshortening_matrix(beam, basis, x + h) - foreshortening_matrix(beam, basis, x - h)) / (2 * h);
    const Eigen::RowVectorXd d = basis.slope(x);
    const Eigen::MatrixXd F = d.transpose() * d;
    // d/dx ∫_0^x = integrand on the right, -integrand on the left (H grows away from o);
    // central differences: h^2 |F''| ~ 1e-10 * 1e3 relative to |F| ~ 1e2 (measured 3e-9)
    INFO("x = " << x << ": " << rel((x > 0 ? 1.0 : -1.0) * dH, F));
    CHECK(rel((x > 0 ? 1.0 : -1.0) * dH, F) < 1e-6);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(foreshortening_matrix(beam, basis, x));
    CHECK(es.eigenvalues().minCoeff() > -1e-12 * es.eigenvalues().maxCoeff());  // PSD up to round-off
  }
}

TEST_CASE("H_bar and G_c equal their definitions integrated directly (nested quadrature)", "[model]") {
  // The rich beam: two segments, o off the mass centre, a hub and a tip mass.
  const BeamProperties p = freeflex_test::rich_beam();
  const Beam beam(p);
  const int n = 6;
  const AdmissibleBasis basis = make_basis(beam, n);
  const StiffeningIntegrals s = stiffening_integrals(beam, basis);
  // H(x) by its own nested quadrature, cut at the segment junction (x = 0.15) and o
  const double xj = 0.6 - 0.45;
  auto F = [&](double x) {
    const Eigen::RowVectorXd d = basis.slope(x);
    return Eigen::MatrixXd(d.transpose() * d);
  };
  auto H = [&](double x) {
    if (x >= 0.0) {
      if (x <= xj) return integrate(0.0, x, 8, n, F);
      return Eigen::MatrixXd(integrate(0.0, xj, 8, n, F) + integrate(xj, x, 8, n, F));
    }
    return integrate(x, 0.0, 8, n, F);
  };
  // sgn(x) H(x) dm and |x| H(x) dm over the distributed mass (segments [-0.45, 0.15] at
  // 1.2 kg/m and [0.15, 0.65] at 0.7 kg/m), then the tip mass 0.25 kg at x = 0.65
  auto Hbar_d = [&](double x) { return Eigen::MatrixXd((x > 0 ? 1.0 : -1.0) * beam.mass_per_length(x) * H(x)); };
  auto Gc_d = [&](double x) { return Eigen::MatrixXd(std::abs(x) * beam.mass_per_length(x) * H(x)); };
  const double xl = beam.x_left(), xr = beam.x_right();
  REQUIRE(xr == Approx(0.65));
  const Eigen::MatrixXd Hbar_ref = integrate(xl, 0.0, 6, n, Hbar_d) + integrate(0.0, xj, 4, n, Hbar_d) +
                                   integrate(xj, xr, 6, n, Hbar_d) + 0.25 * H(xr);
  const Eigen::MatrixXd Gc_ref = integrate(xl, 0.0, 6, n, Gc_d) + integrate(0.0, xj, 4, n, Gc_d) +
                                 integrate(xj, xr, 6, n, Gc_d) + 0.25 * xr * H(xr);
  INFO("H_bar rel " << rel(s.H_bar, Hbar_ref) << ", G_c rel " << rel(s.G_c, Gc_ref));
  // two converged quadratures of smooth integrands (the nested one O(1e3) terms): 1e-10
  CHECK(rel(s.H_bar, Hbar_ref) < 1e-10);
  CHECK(rel(s.G_c, Gc_ref) < 1e-10);
  // G_c is positive semidefinite (a centrifugal tension stiffens every deflection)
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(s.G_c);
  CHECK(es.eigenvalues().minCoeff() > 0.0);
}

TEST_CASE("uniform cantilever: the classical centrifugal tension rho A (L^2 - x^2) / 2", "[model]") {
  // o at the left end: G_c = ∫ N(ξ) Φ'ᵀΦ' dξ with N(ξ) = ρA (L² − ξ²)/2 per unit θ'², and
  // H_bar = ∫ ρA (L − ξ) Φ'ᵀΦ' dξ per unit axial acceleration
  BeamProperties p = BeamProperties::uniform(10.0, 12.0, 14000.0);
  p.reference_m = 0.0;
  const Beam beam(p);
  const int n = 5;
  const AdmissibleBasis basis = make_basis(beam, n);
  const StiffeningIntegrals s = stiffening_integrals(beam, basis);
  auto F = [&](double x) {
    const Eigen::RowVectorXd d = basis.slope(x);
    return Eigen::MatrixXd(d.transpose() * d);
  };
  const Eigen::MatrixXd Gc_ref = integrate(0.0, 10.0, 40, n, [&](double x) { return Eigen::MatrixXd(0.6 * (100.0 - x * x) * F(x)); });
  const Eigen::MatrixXd Hb_ref = integrate(0.0, 10.0, 40, n, [&](double x) { return Eigen::MatrixXd(1.2 * (10.0 - x) * F(x)); });
  INFO("G_c rel " << rel(s.G_c, Gc_ref) << ", H_bar rel " << rel(s.H_bar, Hb_ref));
  CHECK(rel(s.G_c, Gc_ref) < 1e-12);   // two Gauss rules of a smooth integrand: round-off
  CHECK(rel(s.H_bar, Hb_ref) < 1e-12);
  // Mode 1: the cantilever mode is the exact mode at rest, so G_c11 / M11 = dω²/dΩ² at
  // Ω = 0 of the flapwise mode, the Southwell coefficient 1.1933 (flapwise rows of
  // tests/reference: (3.68165² − 3.51602²)/1² = 1.1922 at γ = 1, tending to 1.1933).
  const ModalIntegrals mi = modal_integrals(beam, basis);
  CHECK(s.G_c(0, 0) / mi.M(0, 0) == Approx(1.1933).epsilon(1e-3));  // the exact mode at rest: first-order perturbation exact; 1.1933 printed to 5 digits
}

TEST_CASE("beam symmetric about o: the parity of H_bar and G_c", "[model]") {
  // Φ'_iΦ'_j is even in x when φ_i, φ_j have the same parity, odd otherwise; H(x) then
  // has that parity too, so sgn(x) H(x) integrates to zero over a symmetric beam for
  // equal parities (H_bar couples symmetric and antisymmetric functions only: an axial
  // acceleration of o stretches one half and compresses the other), and |x| H(x) for
  // unequal ones (G_c keeps them apart: the centrifugal tension is symmetric).
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  const StiffeningIntegrals s = stiffening_integrals(beam, make_basis(beam, 8));
  const double scale = s.G_c.cwiseAbs().maxCoeff();
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) {
      INFO(i << ", " << j);
      // round-off of sums of +-equal halves
      if ((i + j) % 2 == 0) CHECK(std::abs(s.H_bar(i, j)) < 1e-12 * scale);
      else CHECK(std::abs(s.G_c(i, j)) < 1e-12 * scale);
    }
  CHECK(s.H_bar.cwiseAbs().maxCoeff() > 0.1 * scale);
}

TEST_CASE("tapered beam on the finite-element basis: H_bar and G_c equal their definitions", "[model]") {
  // Through the ShapeBasis interface with a basis whose slopes are piecewise polynomials and
  // a mass varying linearly (tests/reference/README.md section B: m(s) = 1.2 - 0.8 s kg/m,
  // 0.05 kg at the tip), o inside at s = 0.4; the elements' own modes (free-free) and those
  // clamped at o.
  BeamProperties p = freeflex_test::tapered_beam(true);
  p.reference_m = 0.4;
  const Beam beam(p);
  const int n = 6;
  const auto modes = GENERATE(FiniteElementOptions::Modes::FreeFree, FiniteElementOptions::Modes::ClampedAtReference);
  const auto basis = make_basis(beam, n, BasisOptions{BasisOptions::Kind::FiniteElement, FiniteElementOptions{8, 5, modes}});
  const StiffeningIntegrals s = stiffening_integrals(beam, *basis);
  // Φ'ᵀΦ' is a polynomial of degree 8 on each element, H(x) of degree 9 and m(x) H(x) of
  // degree 10: 12-point Gauss on each element integrates them exactly.
  std::vector<double> cuts = basis->cuts();
  const double xl = beam.x_left(), xr = beam.x_right();
  auto pieces = [&](double a, double b, auto f) {
    std::vector<double> at{a};
    for (double c : cuts)
      if (c > a && c < b) at.push_back(c);
    at.push_back(b);
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(n, n);
    for (std::size_t i = 0; i + 1 < at.size(); ++i) sum += integrate(at[i], at[i + 1], 1, n, f);
    return sum;
  };
  auto F = [&](double x) {
    const Eigen::RowVectorXd d = basis->slope(x);
    return Eigen::MatrixXd(d.transpose() * d);
  };
  auto H = [&](double x) { return x >= 0.0 ? pieces(0.0, x, F) : pieces(x, 0.0, F); };
  auto Hbar_d = [&](double x) { return Eigen::MatrixXd((x > 0 ? 1.0 : -1.0) * beam.mass_per_length(x) * H(x)); };
  auto Gc_d = [&](double x) { return Eigen::MatrixXd(std::abs(x) * beam.mass_per_length(x) * H(x)); };
  const Eigen::MatrixXd Hbar_ref = pieces(xl, 0.0, Hbar_d) + pieces(0.0, xr, Hbar_d) + 0.05 * H(xr);
  const Eigen::MatrixXd Gc_ref = pieces(xl, 0.0, Gc_d) + pieces(0.0, xr, Gc_d) + 0.05 * xr * H(xr);
  INFO("H_bar rel " << rel(s.H_bar, Hbar_ref) << ", G_c rel " << rel(s.G_c, Gc_ref));
  // both exact for the polynomials: round-off of sums of O(1e2) terms
  CHECK(rel(s.H_bar, Hbar_ref) < 1e-11);
  CHECK(rel(s.G_c, Gc_ref) < 1e-11);
  CHECK(s.G_c.cwiseAbs().maxCoeff() > 0.1);
}

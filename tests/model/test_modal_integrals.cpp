// Modal integrals (docs/theory.md section 3) of the uniform beam against closed forms.
#include <catch2/catch.hpp>

#include <cmath>

#include "freeflex/model/modal_integrals.hpp"

using namespace freeflex;

TEST_CASE("uniform beam: m, S_o, I_o exact, parity of Phi_bar and Phi_tilde", "[model]") {
  const double L = 1.7, mass = 2.3, EI = 4.1;
  const Beam beam(BeamProperties::uniform(L, mass, EI));
  REQUIRE(beam.reference_s() == Approx(L / 2).epsilon(1e-15));  // the centre of a uniform beam: one rounding
  const ModalIntegrals mi = modal_integrals(beam, make_basis(beam, 12));
  // rigid integrals are closed forms: round-off only
  CHECK(std::abs(mi.m - mass) <= 1e-14 * mass);
  CHECK(std::abs(mi.S_o) <= 1e-14 * mass * L);
  CHECK(std::abs(mi.I_o - mass * L * L / 12) <= 1e-14 * mass * L * L / 12);
  for (int j = 0; j < 12; ++j) {
    // quadrature sums of +-equal halves: round-off of ~1e3 terms of size mass
    if (j % 2 == 1) CHECK(std::abs(mi.Phi_bar(j)) < 1e-13 * mass);      // antisymmetric
    else CHECK(std::abs(mi.Phi_tilde(j)) < 1e-13 * mass * L);           // symmetric
  }
  // Cantilever orthogonality on each half: M = mbar * (L/2) * 2 * I = m I, K diagonal
  // with EI beta^4 (L/2) * 2 (tolerances: quadrature round-off relative to the diagonal).
  const Eigen::MatrixXd Mref = mass * Eigen::MatrixXd::Identity(12, 12);
  CHECK((mi.M - Mref).cwiseAbs().maxCoeff() < 1e-12 * mass);
  for (int j = 0; j < 12; ++j) {
    const double beta = cantilever_root(j / 2 + 1) / (L / 2);
    CHECK(mi.K(j, j) == Approx(EI * std::pow(beta, 4) * L).epsilon(1e-12));
  }
  // a symmetric function has int psi dx = 2 a sigma / lambda ... checked in closed form:
  // int_0^a psi_k = a * 2 sigma_k / lambda_k (from psi'' integrated twice), so Phi_bar_{2k-1} = 2 mbar a 2 sigma/lambda
  for (int k = 1; k <= 6; ++k) {
    const CantileverConstants c(k);
    const double a = L / 2, mbar = mass / L;
    // Gauss quadrature of a smooth integrand, converged: round-off of ~1e3 terms
    CHECK(mi.Phi_bar(2 * (k - 1)) == Approx(2 * mbar * a * 2 * c.sigma / c.lambda).epsilon(1e-12));
  }
}

TEST_CASE("NOA = 60: M symmetric positive definite and well conditioned", "[model]") {
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  const ModalIntegrals mi = modal_integrals(beam, make_basis(beam, 60));
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(mi.M);
  INFO("eigenvalues of M in [" << es.eigenvalues().minCoeff() << ", " << es.eigenvalues().maxCoeff() << "]");
  // M = m I up to quadrature round-off (measured 1e-14): the scaled cantilever functions keep
  // their digits at lambda ~ 94, where the cosh - sinh form would lose all of them (e^94 ~ 1e40)
  CHECK(es.eigenvalues().minCoeff() > 1.0 - 1e-12);
  CHECK(es.eigenvalues().maxCoeff() < 1.0 + 1e-12);
}

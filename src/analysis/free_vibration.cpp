// Free vibration of the unconstrained beam: mass and stiffness at rest, modes and
// frequencies, the paper's λ.
#include "freeflex/analysis/free_vibration.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

namespace freeflex {

Eigen::MatrixXd rest_mass_matrix(const ModalIntegrals& mi) {
  const int n = mi.size();
  Eigen::MatrixXd M0 = Eigen::MatrixXd::Zero(3 + n, 3 + n);
  // eq. 4.1 at theta = 0, q = 0: M_RR = m I, M_Rtheta = J s0 = [0, S_o],
  // M_Rq = e2 Phi_bar, M_thetatheta = I_o, M_thetaq = Phi_tilde, M_qq = M.
  M0(0, 0) = mi.m;
  M0(1, 1) = mi.m;
  M0(1, 2) = M0(2, 1) = mi.S_o;
  M0(2, 2) = mi.I_o;
  M0.block(1, 3, 1, n) = mi.Phi_bar;
  M0.block(3, 1, n, 1) = mi.Phi_bar.transpose();
  M0.block(2, 3, 1, n) = mi.Phi_tilde;
  M0.block(3, 2, n, 1) = mi.Phi_tilde.transpose();
  M0.block(3, 3, n, n) = mi.M;
  return M0;
}

Eigen::MatrixXd rest_stiffness_matrix(const ModalIntegrals& mi) {
  const int n = mi.size();
  Eigen::MatrixXd K0 = Eigen::MatrixXd::Zero(3 + n, 3 + n);
  K0.block(3, 3, n, n) = mi.K;
  return K0;
}

Eigen::VectorXd spinning_frequencies_squared(const ModalIntegrals& mi, double spin, bool stiffening) {
  if (!std::isfinite(spin))
    throw std::invalid_argument("spinning_frequencies_squared: spin_rad_s = " + std::to_string(spin) +
                                ", expected a finite value");
  if (stiffening && mi.G_c.rows() != mi.size())
    throw std::invalid_argument("spinning_frequencies_squared: the integrals have no G_c (use stiffened_modal_integrals)");
  Eigen::MatrixXd Ks = mi.K - spin * spin * mi.M;
  if (stiffening) Ks += spin * spin * mi.G_c;
  Ks = 0.5 * (Ks + Ks.transpose()).eval();
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Ks, mi.M, Eigen::EigenvaluesOnly);
  if (es.info() != Eigen::Success) throw std::runtime_error("spinning_frequencies_squared: M is not positive definite");
  return es.eigenvalues();
}

FreeVibrationResult free_vibration(const ModalIntegrals& mi) {
  const int n = mi.size();
  const Eigen::MatrixXd M0 = rest_mass_matrix(mi);
  const Eigen::MatrixXd K0 = rest_stiffness_matrix(mi);
  Eigen::LLT<Eigen::MatrixXd> llt(M0);
  if (llt.info() != Eigen::Success)
    throw std::runtime_error("free_vibration: the mass matrix is not positive definite");
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(K0, M0, Eigen::ComputeEigenvectors | Eigen::Ax_lBx);
  if (es.info() != Eigen::Success) throw std::runtime_error("free_vibration: eigensolver failed");
  // Eigenvalues come ascending: the three rigid modes first (zero up to round-off).
  FreeVibrationResult r;
  r.rigid_eigenvalues = es.eigenvalues().head<3>();
  r.omega = es.eigenvalues().tail(n).cwiseMax(0.0).cwiseSqrt();
  r.shapes = es.eigenvectors().rightCols(n);
  return r;
}

double paper_lambda(double omega, double mass_kg, double length_m, double ei) {
  return std::sqrt(omega * std::sqrt(mass_kg * length_m * length_m * length_m / ei));
}

Eigen::VectorXd mode_displacement(const ShapeBasis& basis, const Eigen::VectorXd& z,
                                  const Eigen::VectorXd& x) {
  const int n = basis.size();
  if (z.size() != 3 + n)
    throw std::invalid_argument("mode_displacement: expected an eigenvector of size " +
                                std::to_string(3 + n) + ", got " + std::to_string(z.size()));
  Eigen::VectorXd w(x.size());
  for (int i = 0; i < x.size(); ++i) w(i) = z(1) + x(i) * z(2) + basis.value(x(i)).dot(z.tail(n));
  return w;
}

}  // namespace freeflex

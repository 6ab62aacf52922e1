#pragma once
// Free vibration of the unconstrained beam (docs/theory.md section 5): the linearized
// model about rest, 𝕄0 z'' + 𝕂 z = 0 with z = [Rx, Ry, theta, q] (3 + n), has three
// rigid modes at zero frequency and n elastic modes.
#include <Eigen/Dense>

#include "freeflex/model/basis.hpp"
#include "freeflex/model/modal_integrals.hpp"

namespace freeflex {

/// Mass matrix at theta = 0, q = 0 (eq. 4.1 evaluated at rest), (3+n) x (3+n).
Eigen::MatrixXd rest_mass_matrix(const ModalIntegrals& mi);
/// Stiffness: K in the q block, zero elsewhere.
Eigen::MatrixXd rest_stiffness_matrix(const ModalIntegrals& mi);

struct FreeVibrationResult {
  Eigen::Vector3d rigid_eigenvalues;  ///< omega^2 of the three rigid modes (round-off) [rad^2/s^2]
  Eigen::VectorXd omega;              ///< n elastic natural frequencies, ascending [rad/s]
  Eigen::MatrixXd shapes;             ///< (3+n) x n elastic eigenvectors, mass-normalized
};

/// Solves K v = omega^2 M v. Throws std::runtime_error if the mass matrix is not
/// positive definite (a model error, not user input).
FreeVibrationResult free_vibration(const ModalIntegrals& mi);

/// Elastic frequencies under steady spin Ω about o with the reference frame held (a hub
/// turning at a constant rate; docs/theory.md eq. 14.12): the eigenvalues ω² of
/// (K − Ω² (M − G_c), M), ascending; without stiffening, of (K − Ω² M, M) (each mode
/// then softens as ω² = ω0² − Ω²). A negative ω² is a mode the spin has buckled. `mi`
/// needs G_c (stiffened_modal_integrals) when `stiffening`. Throws std::invalid_argument
/// for a spin that is not finite or G_c missing.
Eigen::VectorXd spinning_frequencies_squared(const ModalIntegrals& mi, double spin_rad_s, bool stiffening);

inline double to_hz(double omega_rad_s) { return omega_rad_s / (2.0 * M_PI); }

/// The paper's Table 1 quantity lambda = sqrt(omega sqrt(m L^3 / EI)) (dimensionless; the
/// paper labels it Hz). m is the beam's total mass, EI its length-weighted mean.
double paper_lambda(double omega_rad_s, double mass_kg, double length_m, double ei_Nm2);

/// Transverse displacement (body y) of a mode at body points x at rest:
/// Ry + x theta + Phi(x) q, from an eigenvector z = [Rx, Ry, theta, q].
Eigen::VectorXd mode_displacement(const ShapeBasis& basis, const Eigen::VectorXd& z,
                                  const Eigen::VectorXd& x);

}  // namespace freeflex

#pragma once
// Steady-state LQR: the continuous algebraic Riccati equation (CARE)
//   Aᵀ P + P A − P S P + Q = 0,   S = B R⁻¹ Bᵀ,   K = R⁻¹ Bᵀ P,   u = −K x,
// minimizing ∫ (xᵀ Q x + uᵀ R u) dt for x' = A x + B u.
//
// Method: the stable invariant subspace of the Hamiltonian H = [[A, −S], [−Q, −Aᵀ]]
// (complex Schur form, reordered by Givens swaps so the n eigenvalues with Re < 0 come
// first; P = Y X⁻¹ from the basis [X; Y]), then Newton–Kleinman polishing
// (Aₖᵀ ΔP + ΔP Aₖ = −Res(Pₖ), Aₖ = A − S Pₖ) until the residual stops falling.
//
// Free-free beams have rigid-body modes (double integrators). Transverse thrusters and
// torques cannot move the body along its own axis x, so with Q weighting R1 the pair
// (A, B) is not stabilizable and no stabilizing solution exists. The uncontrollable modes
// that are not asymptotically stable are found cluster by cluster (each cluster of
// non-stable eigenvalues split off by a reordered Schur form of the balanced Aᵀ, then a
// dual PBH staircase on that small block); `restrict_to_controllable` then solves the
// CARE on the A-invariant complement of those modes and leaves them with zero gain.
#include <complex>
#include <string>

#include <Eigen/Dense>

#include "freeflex/dynamics/flexible_body.hpp"
#include "freeflex/enum_names.hpp"

namespace freeflex {

struct CareOptions {
  /// Solve without the uncontrollable modes that are not asymptotically stable (otherwise
  /// such a problem ends with Status::NotStabilizable).
  bool restrict_to_controllable = false;
  /// Rank tolerance of the per-cluster staircase, relative to ‖B‖ and ‖A‖ (after diagonal
  /// balancing of A).
  double controllability_tolerance = 1e-10;
  /// Hamiltonian eigenvalues with |Re λ| <= this times |λ| (plus 1e3 ε ‖H‖) count as
  /// imaginary: no stabilizing solution.
  double imaginary_axis_tolerance = 1e-8;
  int max_newton_iterations = 8;
};

/// Throws std::invalid_argument naming the first setting out of range; the defaults are
/// valid.
void validate(const CareOptions& options);

struct CareResult {
  enum class Status {
    Solved,                ///< P is the stabilizing solution (on the controllable subspace if reduced)
    NotStabilizable,       ///< uncontrollable modes with Re λ >= 0 and no reduction requested
    NoStabilizingSolution, ///< Hamiltonian eigenvalues on the imaginary axis ((Q, A) not detectable)
    Failed,                ///< numerical breakdown (singular basis, non-finite values)
  };
  Status status = Status::Failed;
  std::string message;
  Eigen::MatrixXd P;                       ///< n x n, symmetric
  Eigen::MatrixXd K;                       ///< m x n, R⁻¹ Bᵀ P
  Eigen::VectorXcd closed_loop_eigenvalues;  ///< of A − B K (uncontrollable ones included)
  /// ‖Vᵀ(Aᵀ P + P A − P S P + Q)V‖_F / ‖VᵀQV‖_F with V the subspace solved on (the
  /// identity when not reduced); divided by ‖P S P‖_F instead when VᵀQV = 0.
  double residual = 0.0;
  double residual_before_newton = 0.0;     ///< the same after the Schur step alone
  /// Normwise backward residual ‖Res‖_F / (‖Q‖_F + 2‖AᵀP‖_F + ‖PSP‖_F): round-off level
  /// (~n ε) whenever the method worked, even when ‖P‖ ≫ ‖Q‖ makes `residual` large.
  double residual_normwise = 0.0;
  int newton_iterations = 0;
  int uncontrollable_dimension = 0;        ///< uncontrollable modes with Re λ >= −δ (not asymptotically stable)
  Eigen::VectorXcd uncontrollable_eigenvalues;
  bool ok() const { return status == Status::Solved; }
};

/// Solves the CARE. Throws std::invalid_argument for mismatched sizes, non-finite
/// entries, Q not symmetric positive semidefinite or R not symmetric positive definite
/// (see check_lqr_weights).
CareResult solve_care(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::MatrixXd>& B,
                      const Eigen::Ref<const Eigen::MatrixXd>& Q, const Eigen::Ref<const Eigen::MatrixXd>& R,
                      const CareOptions& options = {});

/// Throws std::invalid_argument naming `where` unless `W` is `n` x `n`, finite,
/// symmetric (‖W − Wᵀ‖_max <= 1e-10 ‖W‖_max) and positive semidefinite: its smallest
/// eigenvalue must be >= −1e-10 times its largest |eigenvalue| (round-off of a PSD
/// matrix assembled in floating point). Message e.g. "tvlqr: Q must be positive
/// semidefinite: smallest eigenvalue -0.3".
void check_positive_semidefinite(const Eigen::Ref<const Eigen::MatrixXd>& W, int n, const std::string& name,
                                 const std::string& where);
/// As above, but positive definite: smallest eigenvalue > 1e-14 times the largest (R must
/// be invertible in double precision).
void check_positive_definite(const Eigen::Ref<const Eigen::MatrixXd>& W, int n, const std::string& name,
                             const std::string& where);

/// Weight on x1 = [R1 (2), θ1, q (n), R1', θ1', q'] for vibration suppression:
///   x1ᵀ Q x1 = w_elastic (qᵀ K q + q'ᵀ M q') + w_rigid_pos (|R1|² + θ1²) + w_rigid_rate (|R1'|² + θ1'²),
/// i.e. blockdiag(w_rigid_pos I₃, w_elastic K, w_rigid_rate I₃, w_elastic M) (K, M of eq. 3.2).
/// The elastic term is twice the elastic energy (with M instead of the condensed mass).
/// Units: w_elastic [1/J per J], w_rigid_pos per m² or rad², w_rigid_rate per (m/s)² or
/// (rad/s)². Throws std::invalid_argument if a weight is negative or not finite.
Eigen::MatrixXd vibration_weight(const FlexibleBody& body, double w_elastic, double w_rigid_pos, double w_rigid_rate);

template <>
struct EnumNames<CareResult::Status> {
  static constexpr const char* what = "CARE status";
  static constexpr std::array<std::pair<CareResult::Status, const char*>, 4> names{
      {{CareResult::Status::Solved, "solved"},
       {CareResult::Status::NotStabilizable, "not_stabilizable"},
       {CareResult::Status::NoStabilizingSolution, "no_stabilizing_solution"},
       {CareResult::Status::Failed, "failed"}}};
};

}  // namespace freeflex

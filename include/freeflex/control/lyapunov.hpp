#pragma once
// Continuous Lyapunov equations Aᵀ X + X A + C = 0 (Bartels–Stewart, real Schur form).
// The factor-once solvers the CARE polish and the TV-LQR use are private to src/
// (control/lyapunov_solvers.hpp).
#include <Eigen/Dense>

namespace freeflex {

/// X with Aᵀ X + X A + C = 0 (A stable gives the unique solution; C symmetric gives X
/// symmetric). Throws std::invalid_argument for mismatched sizes and std::runtime_error
/// when the equation is singular (A and −A share an eigenvalue).
Eigen::MatrixXd solve_lyapunov(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::MatrixXd>& C);

}  // namespace freeflex

#pragma once
// Allocation-free forms of FlexibleBody's generalized forces for the right-hand sides
// that run tens of thousands of times per simulated second: they add into buffers the
// caller keeps. FlexibleBody::element_force is the reference they are tested against.
// Private to src/.
#include <vector>

#include <Eigen/Dense>

#include "freeflex/dynamics/flexible_body.hpp"

namespace freeflex::detail {

/// Adds scale times the generalized force of element e at (theta, q) to G and, if dG is
/// given, scale times its derivative along (d_theta, d_q) to dG (d_q null: zero).
void add_element_force(const FlexibleBody& body, int e, double theta, const Eigen::Ref<const Eigen::VectorXd>& q,
                       double scale, Eigen::Ref<Eigen::VectorXd> G, double d_theta = 0.0,
                       const Eigen::VectorXd* d_q = nullptr, Eigen::VectorXd* dG = nullptr);

/// G = Σ_e commands(e) element_force(e, theta, q) (elements with a zero command skipped).
void generalized_force(const FlexibleBody& body, double theta, const Eigen::Ref<const Eigen::VectorXd>& q,
                       const Eigen::Ref<const Eigen::VectorXd>& commands, Eigen::Ref<Eigen::VectorXd> G);

/// Each element's Φ(x_e) and Φ'(x_e) in other elastic coordinates η, q = Ψ η: the rows
/// Φ(x_e) Ψ and Φ'(x_e) Ψ, and with geometric stiffening its foreshortening Ψᵀ H(x_e) Ψ.
/// With them the functions below give the generalized force in those coordinates,
/// [F; M_o; Ψᵀ Q] (the forces of sections 6 and 14 are linear in the rows, quadratic
/// forms in H).
struct ElementRows {
  std::vector<Eigen::RowVectorXd> phi, slope;
  std::vector<Eigen::MatrixXd> H;  ///< empty matrices without geometric stiffening
  ElementRows() = default;
  ElementRows(const FlexibleBody& body, const Eigen::MatrixXd& Psi);
};

/// add_element_force with element e's rows taken from `rows` and q the coordinates they
/// are rows of.
void add_element_force(const FlexibleBody& body, const ElementRows& rows, int e, double theta,
                       const Eigen::Ref<const Eigen::VectorXd>& q, double scale, Eigen::Ref<Eigen::VectorXd> G);

/// generalized_force in the coordinates of `rows`.
void generalized_force(const FlexibleBody& body, const ElementRows& rows, double theta,
                       const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& commands,
                       Eigen::Ref<Eigen::VectorXd> G);

}  // namespace freeflex::detail

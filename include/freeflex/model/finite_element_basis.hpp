#pragma once
// The finite-element basis (docs/theory.md section 2b): the lowest free-free elastic
// modes of a beam-element model of the whole beam, each with its rigid part at o
// removed, kept as the shape functions of the hybrid model:
//
//   phi_k(x) = sqrt(m) (v_k(x) - v_k(0) - x v_k'(0)),   k = 1..n                  (eq. 2.6)
//
// v_k the k-th elastic free-free mode of the element model (mass-normalized), m the total
// mass. Φ(0) = Φ'(0) = 0, and the rigid coordinates with Φ span exactly the element
// model's rigid and first n elastic modes, so the hybrid model's free vibration
// reproduces the element model's lowest n frequencies.
//
// Elements: Hermite cubics (w, w' at each node; C¹), optionally enriched by two
// hierarchical bubbles per element whose curvatures are the Legendre polynomials P2, P3
// in the element coordinate (order 5: the complete quintic, still C¹, so curvature may
// jump where EI jumps). Nodes at both ends, every segment junction, every point mass and
// o; the remaining elements subdivide these intervals as evenly as possible. Consistent
// mass of the distributed mass (linear along a tapered segment), point masses on their
// nodes, the hub's mass and rotary inertia on the node at o.
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/model/beam.hpp"
#include "freeflex/model/shape_basis.hpp"

namespace freeflex {

/// Largest element count a finite-element basis accepts.
inline constexpr int kMaxElements = 2000;

struct FiniteElementOptions {
  /// Number of elements (at least one per interval between nodes the beam requires; a
  /// smaller count is raised to that).
  int elements = 100;
  /// 3: Hermite cubics, error in ω falling as h^4; 5: cubics and two bubbles, as h^8.
  int order = 5;
  /// Throws std::invalid_argument naming the field if elements is outside [1,
  /// kMaxElements] or order is neither 3 nor 5.
  void validate() const;
};

class FiniteElementBasis : public ShapeBasis {
 public:
  /// The first n elastic modes of the beam's element model. Throws std::invalid_argument
  /// for bad options or n outside [1, element model's elastic mode count], and
  /// std::runtime_error if the eigensolver does not converge.
  FiniteElementBasis(const Beam& beam, int n, FiniteElementOptions options = {});

  int size() const override { return static_cast<int>(omega_.size()); }
  BasisValues evaluate(double x) const override;
  /// The interior nodes: curvature jumps there.
  std::vector<double> cuts() const override;
  /// +inf: each element is one polynomial, one panel per element integrates it exactly.
  double max_panel_width() const override;
  std::string name() const override { return "finite_element"; }

  const FiniteElementOptions& options() const { return options_; }
  /// Elements actually used (options().elements, raised to one per required interval).
  int elements() const { return static_cast<int>(nodes_.size()) - 1; }
  /// Node positions (body x), ascending, both ends included.
  const std::vector<double>& nodes() const { return nodes_; }
  /// Degrees of freedom of the element model.
  int dofs() const { return dofs_; }
  /// The element model's own elastic frequencies of the kept modes [rad/s], ascending.
  const Eigen::VectorXd& element_model_omega() const { return omega_; }
  /// Subspace iterations the eigensolver took.
  int iterations() const { return iterations_; }

 private:
  FiniteElementOptions options_;
  std::vector<double> nodes_;
  int dofs_ = 0;
  int per_element_ = 4;     // local DOFs: 4 (cubic) or 6 (with bubbles)
  Eigen::MatrixXd coef_;    // (elements * per_element) x n: each element's local DOFs of Φ
  Eigen::VectorXd omega_;
  int iterations_ = 0;
};

}  // namespace freeflex

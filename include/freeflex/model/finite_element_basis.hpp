#pragma once
// The finite-element basis (docs/theory.md section 2b): the lowest modes of a
// beam-element model of the whole beam, kept as the shape functions of the hybrid model.
// By default the free-free elastic modes, each with its rigid part at o removed:
//
//   phi_k(x) = sqrt(m) (v_k(x) - v_k(0) - x v_k'(0)),   k = 1..n                  (eq. 2.6)
//
// v_k the k-th elastic free-free mode of the element model (mass-normalized), m the total
// mass. Φ(0) = Φ'(0) = 0, and the rigid coordinates with Φ span exactly the element
// model's rigid and first n elastic modes, so the hybrid model's free vibration
// reproduces the element model's lowest n frequencies.
//
// Or (modes = ClampedAtReference) the modes of the element model clamped at o (w and w'
// of o's node held at zero): each side of o is then a cantilever, each mode lives on one
// side, and the two sides' modes are merged by frequency (eq. 2.7). These are the paper's
// kind of function (for the uniform beam with o at the centre, its very functions to the
// discretization error): curvature and shear may jump at o, which a moment or force
// applied at o asks for.
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

#include "freeflex/enum_names.hpp"
#include "freeflex/model/beam.hpp"
#include "freeflex/model/shape_basis.hpp"

namespace freeflex {

/// Largest element count a finite-element basis accepts.
inline constexpr int kMaxElements = 2000;

struct FiniteElementOptions {
  /// Which modes of the element model the basis keeps (docs/theory.md sections 2b, 4b).
  enum class Modes {
    FreeFree,            ///< free-free elastic modes, rigid part at o removed: exact frequencies
    ClampedAtReference,  ///< modes clamped at o: point loads and moments at o converge fast
  };
  /// Number of elements (at least one per interval between nodes the beam requires; a
  /// smaller count is raised to that).
  int elements = 100;
  /// 3: Hermite cubics, error in ω falling as h^4; 5: cubics and two bubbles, as h^8.
  int order = 5;
  Modes modes = Modes::FreeFree;
  /// Throws std::invalid_argument naming the field if elements is outside [1,
  /// kMaxElements] or order is neither 3 nor 5.
  void validate() const;
};

template <>
struct EnumNames<FiniteElementOptions::Modes> {
  static constexpr const char* what = "fe_modes";
  static constexpr std::array<std::pair<FiniteElementOptions::Modes, const char*>, 2> names{
      {{FiniteElementOptions::Modes::FreeFree, "free_free"},
       {FiniteElementOptions::Modes::ClampedAtReference, "clamped_at_reference"}}};
};

class FiniteElementBasis : public ShapeBasis {
 public:
  /// The first n elastic modes of the beam's element model (free-free or clamped at o). Throws std::invalid_argument
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
  /// The element model's own elastic frequencies of the kept modes [rad/s], ascending
  /// (free-free, or clamped at o: the hybrid model's are then higher).
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

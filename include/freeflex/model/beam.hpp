#pragma once
// The beam: geometry, mass and stiffness per segment (constant, or varying linearly along
// a tapered segment), hub and point masses.
//
// Conventions (docs/theory.md section 1): SI units throughout. Positions given by a
// user are distances `s` from the beam's left end, 0 <= s <= L. The body frame has its
// origin at the reference point o (s = s_o) and body coordinate x = s - s_o, so the
// beam occupies [x_left, x_right] = [-s_o, L - s_o].
#include <optional>
#include <vector>

namespace freeflex {

/// One piece of the beam; pieces are laid end to end from the left end. The mass per
/// length and the stiffness are the values at the piece's left end; given an end value,
/// they vary linearly to it along the piece (a tapered piece), otherwise they are constant.
struct BeamSegment {
  double length_m = 0.0;
  double mass_per_length_kg_m = 0.0;
  double bending_stiffness_Nm2 = 0.0;
  std::optional<double> mass_per_length_end_kg_m = std::nullopt;   ///< at the piece's right end
  std::optional<double> bending_stiffness_end_Nm2 = std::nullopt;  ///< at the piece's right end

  double mass_per_length_end() const { return mass_per_length_end_kg_m.value_or(mass_per_length_kg_m); }
  double bending_stiffness_end() const { return bending_stiffness_end_Nm2.value_or(bending_stiffness_Nm2); }
  bool tapered() const { return mass_per_length_end_kg_m.has_value() || bending_stiffness_end_Nm2.has_value(); }
  double mass() const { return 0.5 * (mass_per_length_kg_m + mass_per_length_end()) * length_m; }
};

/// A concentrated mass (a payload) at distance s from the left end.
struct PointMass {
  double position_m = 0.0;
  double mass_kg = 0.0;
};

/// Everything that defines the structure.
struct BeamProperties {
  std::vector<BeamSegment> segments;
  /// Reference point o as distance from the left end; empty: the mass centre.
  std::optional<double> reference_m;
  double hub_mass_kg = 0.0;             ///< rigid hub at o
  double hub_rotary_inertia_kgm2 = 0.0; ///< about o
  std::vector<PointMass> point_masses;

  /// Uniform beam of length L, total mass m and stiffness EI, o at the centre.
  static BeamProperties uniform(double length_m, double mass_kg, double bending_stiffness_Nm2);

  /// One uniform span (equal, untapered segments), no hub and no payload: the closed-form
  /// free-free beam gives its frequencies exactly.
  bool plain_uniform() const;
};

/// Validated, immutable beam. Construction throws std::invalid_argument naming the
/// offending field when a length, mass or stiffness is not finite and positive, or a
/// position lies outside the beam, or o is not on it (o at an end: a cantilever clamped
/// at o).
class Beam {
 public:
  explicit Beam(BeamProperties props);

  const BeamProperties& properties() const { return props_; }
  double length() const { return length_; }
  /// Position of o from the left end.
  double reference_s() const { return s_o_; }
  double x_left() const { return -s_o_; }
  double x_right() const { return length_ - s_o_; }
  /// Body coordinate of a distance s from the left end.
  double x_of(double s) const { return s - s_o_; }
  /// Distributed mass and stiffness at body coordinate x (right-continuous; linear along a
  /// tapered segment).
  double mass_per_length(double x) const;
  double bending_stiffness(double x) const;
  /// Body coordinates of the ends and of every segment junction, ascending.
  std::vector<double> breakpoints_x() const;
  /// Whether any segment is tapered.
  bool tapered() const;
  /// Distributed mass only (no hub or point masses).
  double distributed_mass() const;
  /// Length-weighted mean EI, used for the non-dimensional frequency lambda.
  double mean_bending_stiffness() const;

 private:
  /// Segment containing body coordinate x (right-continuous) and, if t is given, the
  /// fraction of its length at which x lies.
  const BeamSegment& segment_at(double x, double* t = nullptr) const;
  BeamProperties props_;
  double length_ = 0.0;
  double s_o_ = 0.0;
};

}  // namespace freeflex

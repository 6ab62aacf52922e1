// The beam: validation of its properties, the reference point, mass and stiffness along it.
#include "freeflex/model/beam.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace freeflex {
namespace {

void require_positive(double v, const std::string& what) {
  if (!std::isfinite(v) || !(v > 0.0)) {
    std::ostringstream os;
    os << what << " = " << v << ", must be finite and > 0";
    throw std::invalid_argument(os.str());
  }
}
void require_nonnegative(double v, const std::string& what) {
  if (!std::isfinite(v) || v < 0.0) {
    std::ostringstream os;
    os << what << " = " << v << ", must be finite and >= 0";
    throw std::invalid_argument(os.str());
  }
}

}  // namespace

BeamProperties BeamProperties::uniform(double length_m, double mass_kg, double ei) {
  BeamProperties p;
  p.segments.push_back({length_m, mass_kg / length_m, ei});
  return p;
}

bool BeamProperties::plain_uniform() const {
  for (const auto& s : segments)
    if (s.tapered() || s.mass_per_length_kg_m != segments[0].mass_per_length_kg_m ||
        s.bending_stiffness_Nm2 != segments[0].bending_stiffness_Nm2)
      return false;
  for (const auto& pm : point_masses)
    if (pm.mass_kg != 0.0) return false;
  return hub_mass_kg == 0.0 && hub_rotary_inertia_kgm2 == 0.0;
}

Beam::Beam(BeamProperties props) : props_(std::move(props)) {
  if (props_.segments.empty()) throw std::invalid_argument("beam: at least one segment is required");
  for (std::size_t i = 0; i < props_.segments.size(); ++i) {
    const auto& seg = props_.segments[i];
    const std::string tag = "beam segment " + std::to_string(i + 1);
    require_positive(seg.length_m, tag + " length_m");
    require_positive(seg.mass_per_length_kg_m, tag + " mass_per_length_kg_m");
    require_positive(seg.bending_stiffness_Nm2, tag + " bending_stiffness_Nm2");
    // linear between two positive ends: positive all along
    if (seg.mass_per_length_end_kg_m) require_positive(*seg.mass_per_length_end_kg_m, tag + " mass_per_length_end_kg_m");
    if (seg.bending_stiffness_end_Nm2) require_positive(*seg.bending_stiffness_end_Nm2, tag + " bending_stiffness_end_Nm2");
    length_ += seg.length_m;
  }
  require_nonnegative(props_.hub_mass_kg, "beam hub mass_kg");
  require_nonnegative(props_.hub_rotary_inertia_kgm2, "beam hub rotary_inertia_kgm2");
  for (std::size_t i = 0; i < props_.point_masses.size(); ++i) {
    const auto& pm = props_.point_masses[i];
    const std::string tag = "point mass " + std::to_string(i + 1);
    require_nonnegative(pm.mass_kg, tag + " mass_kg");
    if (!std::isfinite(pm.position_m) || pm.position_m < 0.0 || pm.position_m > length_) {
      std::ostringstream os;
      os << tag << " position_m = " << pm.position_m << ", must lie on the beam [0, " << length_ << "]";
      throw std::invalid_argument(os.str());
    }
  }
  if (props_.reference_m) {
    s_o_ = *props_.reference_m;
  } else {
    // Mass centre of distributed mass and point masses (the hub sits at o and cannot move it).
    double m = 0.0, ms = 0.0, s0 = 0.0;
    for (const auto& seg : props_.segments) {
      if (seg.mass_per_length_end_kg_m) {
        // linear mass: centroid at L (mu_a + 2 mu_b) / (3 (mu_a + mu_b)) from the segment's start
        const double ma = seg.mass_per_length_kg_m, mb = *seg.mass_per_length_end_kg_m;
        const double mi = seg.mass();
        m += mi;
        ms += mi * s0 + seg.length_m * seg.length_m * (ma + 2.0 * mb) / 6.0;
      } else {
        const double mi = seg.mass_per_length_kg_m * seg.length_m;
        m += mi;
        ms += mi * (s0 + 0.5 * seg.length_m);
      }
      s0 += seg.length_m;
    }
    for (const auto& pm : props_.point_masses) {
      m += pm.mass_kg;
      ms += pm.mass_kg * pm.position_m;
    }
    s_o_ = ms / m;
  }
  // o at an end is a cantilever clamped at o (the basis then has one side only)
  if (!std::isfinite(s_o_) || !(s_o_ >= 0.0) || !(s_o_ <= length_)) {
    std::ostringstream os;
    os << "beam reference_m = " << s_o_ << ", must lie on the beam [0, " << length_ << "]";
    throw std::invalid_argument(os.str());
  }
}

const BeamSegment& Beam::segment_at(double x, double* t) const {
  const double s = x + s_o_;
  double s_end = 0.0;
  for (const auto& seg : props_.segments) {
    const double s_start = s_end;
    s_end += seg.length_m;
    if (s < s_end || &seg == &props_.segments.back()) {
      if (t) *t = std::min(1.0, std::max(0.0, (s - s_start) / seg.length_m));  // round-off at the ends
      return seg;
    }
  }
  return props_.segments.back();  // not reached: the loop returns at the last segment
}

double Beam::mass_per_length(double x) const {
  double t = 0.0;
  const BeamSegment& seg = segment_at(x, &t);
  if (!seg.mass_per_length_end_kg_m) return seg.mass_per_length_kg_m;
  return seg.mass_per_length_kg_m + t * (*seg.mass_per_length_end_kg_m - seg.mass_per_length_kg_m);
}

double Beam::bending_stiffness(double x) const {
  double t = 0.0;
  const BeamSegment& seg = segment_at(x, &t);
  if (!seg.bending_stiffness_end_Nm2) return seg.bending_stiffness_Nm2;
  return seg.bending_stiffness_Nm2 + t * (*seg.bending_stiffness_end_Nm2 - seg.bending_stiffness_Nm2);
}

bool Beam::tapered() const {
  for (const auto& seg : props_.segments)
    if (seg.tapered()) return true;
  return false;
}

std::vector<double> Beam::breakpoints_x() const {
  std::vector<double> b{-s_o_};
  double s0 = 0.0;
  for (const auto& seg : props_.segments) {
    s0 += seg.length_m;
    b.push_back(s0 - s_o_);
  }
  b.back() = length_ - s_o_;
  return b;
}

double Beam::distributed_mass() const {
  double m = 0.0;
  for (const auto& seg : props_.segments)
    m += seg.mass_per_length_end_kg_m ? seg.mass() : seg.mass_per_length_kg_m * seg.length_m;
  return m;
}

double Beam::mean_bending_stiffness() const {
  double a = 0.0;
  for (const auto& seg : props_.segments)
    a += (seg.bending_stiffness_end_Nm2 ? 0.5 * (seg.bending_stiffness_Nm2 + *seg.bending_stiffness_end_Nm2)
                                        : seg.bending_stiffness_Nm2) *
         seg.length_m;
  return a / length_;
}

}  // namespace freeflex

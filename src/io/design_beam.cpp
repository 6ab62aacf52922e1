// [beam]: a uniform (or linearly tapered) beam or segments, the reference point o, a hub
// and point masses. A segment's mass per length and stiffness are a number or [start, end]
// (varying linearly along the segment).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "io/design_sections.hpp"

namespace freeflex::io_detail {

void read_beam(Section& root, Design& d) {
  Section b = root.table("beam");
  if (!b.present()) {
    b.problem("beam", "section [beam] is required");
    return;
  }
  BeamProperties& p = d.beam;
  auto segs = b.table_array("segment");
  const bool uniform_keys = b.has("length_m") || b.has("mass_kg") || b.has("mass_per_length_kg_m") ||
                            b.has("bending_stiffness_Nm2");
  if (!segs.empty() && uniform_keys) {
    b.problem("segment", "beam: give either length_m, mass and bending_stiffness_Nm2 (uniform) or "
                         "[[beam.segment]] tables (piecewise), not both");
  } else if (segs.empty()) {
    auto L = b.number("length_m", kLength, true);
    std::optional<std::pair<double, std::optional<double>>> mu;
    if (b.has("mass_kg") && b.has("mass_per_length_kg_m")) {
      b.problem("mass_kg", "beam: give mass_kg or mass_per_length_kg_m, not both");
      b.number("mass_kg", kMass, false);
      b.number_or_pair("mass_per_length_kg_m", kMassPerLength, false);
    } else if (b.has("mass_per_length_kg_m")) {
      mu = b.number_or_pair("mass_per_length_kg_m", kMassPerLength, true);
    } else if (auto mass = b.number("mass_kg", kMass, true); mass && L) {
      mu = std::make_pair(*mass / *L, std::optional<double>());
    }
    auto ei = b.number_or_pair("bending_stiffness_Nm2", kStiffness, true);
    if (L && mu && ei) p.segments.push_back({*L, mu->first, ei->first, mu->second, ei->second});
  } else if (segs.size() > static_cast<std::size_t>(lim::kMaxBeamPieces)) {
    b.problem("segment", "beam: " + std::to_string(segs.size()) + " [[beam.segment]] tables; at most " +
                             std::to_string(lim::kMaxBeamPieces) + " (every study builds the body from them)");
  } else {
    bool ok = true;
    for (auto& s : segs) {
      auto L = s.number("length_m", kLength, true);
      auto mu = s.number_or_pair("mass_per_length_kg_m", kMassPerLength, true);
      auto ei = s.number_or_pair("bending_stiffness_Nm2", kStiffness, true);
      s.finish();
      if (L && mu && ei) p.segments.push_back({*L, mu->first, ei->first, mu->second, ei->second});
      else ok = false;
    }
    if (!ok) p.segments.clear();
    double total = 0.0;
    for (const auto& seg : p.segments) total += seg.length_m;
    if (total > lim::kMaxLength_m)
      b.problem("segment", "beam: the segments add up to " + shortest(total) + " m; at most " +
                               shortest(lim::kMaxLength_m) + " m");
  }
  double length = 0.0, total_mass = 0.0;
  for (const auto& s : p.segments) {
    length += s.length_m;
    total_mass += s.mass_per_length_end_kg_m ? s.mass() : s.mass_per_length_kg_m * s.length_m;
  }
  // mass_kg is checked where it is given; a mass that comes from mass per length is checked here
  if (!p.segments.empty() && (!b.has("mass_kg") || !segs.empty()) &&
      (total_mass < lim::kMinMass_kg || total_mass > lim::kMaxMass_kg))
    b.problem(segs.empty() ? "mass_per_length_kg_m" : "segment",
              "beam: the mass per length gives a beam of " + shortest(total_mass) + " kg; it must be within [" +
                  shortest(lim::kMinMass_kg) + ", " + shortest(lim::kMaxMass_kg) + "] kg (the supported range)");
  const bool have_length = !p.segments.empty();
  const Range on_beam = have_length ? Range::closed(0.0, length) : Range::nonnegative();
  // o at an end (a cantilever clamped at o: one side's functions only), or inside and not
  // within L/1000 of an end: the full model's step count grows like 1/distance^2 there,
  // and at 1e-6 L its modes at rest can no longer be computed
  if (b.has("reference_m")) {
    p.reference_m = b.number("reference_m", have_length ? Range::closed(0.0, length) : Range::nonnegative(), false);
    const double margin = lim::kEndMargin * length;
    if (have_length && p.reference_m && *p.reference_m != 0.0 && *p.reference_m != length &&
        (*p.reference_m < margin || *p.reference_m > length - margin)) {
      b.problem("reference_m", b.key_path("reference_m") + " = " + shortest(*p.reference_m) + ", must be 0 or " +
                                   shortest(length) + " (o at an end: a cantilever clamped at o) or within [" +
                                   shortest(margin) + ", " + shortest(length - margin) + "] (the supported range)");
      p.reference_m.reset();
    }
  }
  Section hub = b.table("hub");
  if (hub.present()) {
    p.hub_mass_kg = hub.number("mass_kg", kMassOrZero, false).value_or(0.0);
    p.hub_rotary_inertia_kgm2 =
        hub.number("rotary_inertia_kgm2", Range::nonnegative().supported(-kInf, lim::kMaxRotaryInertia_kgm2), false)
            .value_or(0.0);
    hub.finish();
  }
  auto masses = b.table_array("point_mass");
  if (masses.size() > static_cast<std::size_t>(lim::kMaxBeamPieces)) {
    b.problem("point_mass", "beam: " + std::to_string(masses.size()) + " [[beam.point_mass]] tables; at most " +
                                std::to_string(lim::kMaxBeamPieces) + " (every study builds the body from them)");
    masses.clear();
  }
  for (auto& s : masses) {
    auto pos = s.number("position_m", on_beam, true);
    auto m = s.number("mass_kg", kMassOrZero, true);
    s.finish();
    if (pos && m) p.point_masses.push_back({*pos, *m});
  }
  b.finish();
}


}  // namespace freeflex::io_detail

// Tapered segments (mass per length and EI linear along a segment, docs/theory.md eq. 3.4):
// the beam's properties, the closed-form m, S_o, I_o and mass centre against an
// independent quadrature, and the paper's basis against tests/reference/'s power series.
#include <catch2/catch.hpp>

#include <cmath>
#include <iomanip>

#include "freeflex/analysis/free_vibration.hpp"
#include "freeflex/model/modal_integrals.hpp"
#include "support/reference_csv.hpp"

using namespace freeflex;

namespace {

// Two tapered segments and a uniform one, a hub and a point mass; o given or the mass centre.
BeamProperties mixed_beam() {
  BeamProperties p;
  BeamSegment a{0.4, 1.0, 3.0}, b{0.5, 0.8, 2.0}, c{0.3, 0.3, 1.0};
  a.mass_per_length_end_kg_m = 0.6;
  a.bending_stiffness_end_Nm2 = 2.5;
  b.bending_stiffness_end_Nm2 = 1.2;  // uniform mass, tapered stiffness
  p.segments = {a, b, c};
  p.hub_mass_kg = 0.2;
  p.hub_rotary_inertia_kgm2 = 0.01;
  p.point_masses = {{1.2, 0.1}};
  return p;
}

}  // namespace

TEST_CASE("tapered segments: properties along the beam are linear within a segment", "[model]") {
  BeamProperties p = mixed_beam();
  p.reference_m = 0.5;
  const Beam beam(p);
  CHECK(beam.tapered());
  // s = 0.1 in segment 1 (a quarter along), 0.65 in segment 2 (half way), 1.0 in segment 3;
  // linear interpolation of two entries: a few ulp
  CHECK(beam.mass_per_length(beam.x_of(0.1)) == Approx(0.9).epsilon(1e-14));
  CHECK(beam.bending_stiffness(beam.x_of(0.1)) == Approx(2.875).epsilon(1e-14));
  CHECK(beam.mass_per_length(beam.x_of(0.65)) == 0.8);
  CHECK(beam.bending_stiffness(beam.x_of(0.65)) == Approx(1.6).epsilon(1e-14));
  CHECK(beam.bending_stiffness(beam.x_of(1.0)) == 1.0);
  CHECK(beam.distributed_mass() == Approx(0.32 + 0.4 + 0.09).epsilon(1e-14));
  CHECK(beam.mean_bending_stiffness() == Approx((0.4 * 2.75 + 0.5 * 1.6 + 0.3 * 1.0) / 1.2).epsilon(1e-14));
  CHECK_FALSE(Beam(BeamProperties::uniform(1.0, 1.0, 1.0)).tapered());
}

TEST_CASE("tapered segments: m, S_o, I_o and the mass centre match an independent quadrature", "[model]") {
  for (const bool explicit_ref : {false, true}) {
    BeamProperties p = mixed_beam();
    if (explicit_ref) p.reference_m = 0.45;
    const Beam beam(p);
    // own quadrature: 3-point Gauss per segment is exact for the quadratic x^2 m(x) times 1
    const double g[3] = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)}, w[3] = {5.0 / 9, 8.0 / 9, 5.0 / 9};
    double m = p.hub_mass_kg + 0.1, ms = 0.1 * 1.2, s0 = 0.0;  // mass and first moment about the left end
    double I_left = 0.1 * 1.2 * 1.2;
    for (const BeamSegment& seg : p.segments) {
      for (int i = 0; i < 3; ++i) {
        const double t = 0.5 * (1 + g[i]), s = s0 + t * seg.length_m;
        const double mu = seg.mass_per_length_kg_m + t * (seg.mass_per_length_end() - seg.mass_per_length_kg_m);
        const double dm = 0.5 * seg.length_m * w[i] * mu;
        m += dm;
        ms += dm * s;
        I_left += dm * s * s;
      }
      s0 += seg.length_m;
    }
    // the hub sits at o and does not move the mass centre of the rest
    const double s_c = ms / (m - p.hub_mass_kg);
    const double s_o = explicit_ref ? 0.45 : s_c;
    INFO(std::setprecision(16) << "s_c " << s_c << ", freeflex s_o " << beam.reference_s());
    // sums of a dozen terms in a different order: a few ulp
    if (!explicit_ref) CHECK(beam.reference_s() == Approx(s_c).epsilon(1e-14));
    const ModalIntegrals mi = modal_integrals(beam, make_basis(beam, 6));
    const double S = ms - (m - p.hub_mass_kg) * s_o;  // hub at o: no first moment
    const double I = I_left - 2 * s_o * ms + (m - p.hub_mass_kg) * s_o * s_o + p.hub_rotary_inertia_kgm2;
    CHECK(mi.m == Approx(m).epsilon(1e-14));
    CHECK(std::abs(mi.S_o - S) <= 1e-14 * m * 1.2);  // absolute: S_o = 0 at the mass centre
    CHECK(mi.I_o == Approx(I).epsilon(1e-13));        // parallel-axis form: cancellation of ~1
  }
}

TEST_CASE("tapered segments: a non-positive end value is rejected with its name", "[model]") {
  BeamProperties p = mixed_beam();
  p.segments[0].mass_per_length_end_kg_m = -0.1;
  CHECK_THROWS_WITH(Beam(p), Catch::Contains("beam segment 1 mass_per_length_end_kg_m = -0.1, must be finite and > 0"));
  p = mixed_beam();
  p.segments[1].bending_stiffness_end_Nm2 = 0.0;
  CHECK_THROWS_WITH(Beam(p), Catch::Contains("beam segment 2 bending_stiffness_end_Nm2 = 0"));
}

TEST_CASE("tapered beam: the paper's basis converges to the power-series frequencies", "[model]") {
  // Measured relative errors (first five modes): bare, NOA 40: <= 5.8e-7; NOA 100: <= 6e-9.
  // With the 0.05 kg tip mass the cantilever functions' free end carries no shear, so they
  // converge slowly: NOA 100: 9.3e-8 (mode 1) .. 3.3e-6 (mode 5); 1e-6 for all five is
  // beyond NOA 100 (the FE basis reaches it with 160 cubic elements, see its tests).
  struct Case {
    bool tip;
    int noa;
    double tol;
  };
  const Case cases[] = {{false, 40, 1e-6}, {true, 100, 5e-6}};
  for (const Case& c : cases) {
    const Beam beam(freeflex_test::tapered_beam(c.tip));
    const Eigen::VectorXd exact =
        freeflex_test::reference_column("tapered_beam_frequencies.csv", c.tip ? "tapered_tip" : "tapered_bare");
    const Eigen::VectorXd omega = free_vibration(modal_integrals(beam, make_basis(beam, c.noa))).omega.head(5);
    const Eigen::VectorXd err = omega.cwiseQuotient(exact).array() - 1.0;
    INFO("tip " << c.tip << ", NOA " << c.noa << ": relative errors " << err.transpose());
    CHECK(err.maxCoeff() <= c.tol);
    CHECK(err.minCoeff() >= 0.0);  // a Ritz upper bound (margins >= 6e-11)
  }
}

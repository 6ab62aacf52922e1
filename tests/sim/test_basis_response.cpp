// Forced responses on the two bases (issue 15, acceptance 2). The paper's moment and force
// examples load the beam at o. The FE basis's modes clamped at o are, on the uniform beam
// with o at the centre, the paper's own functions (to the discretization error), so the
// responses agree at equal even mode counts; its free-free modes span another space, in
// which these examples converge only slowly (docs/theory.md sections 2b, 4b).
#include <catch2/catch.hpp>

#include <cmath>
#include <iomanip>

#include "freeflex/sim/simulate.hpp"

using namespace freeflex;

namespace {

TimeProfile pulse() { return TimeProfile(TimeProfile::Kind::Steps, {0.0, 0.5, 1.0}, {1.0, -1.0}); }

/// The paper's beam with one load at the centre, on the given basis with n functions.
FlexibleBody paper_body(ForceElement::Type type, int n, const BasisOptions& basis) {
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  return FlexibleBody(beam, n, basis, {{"load", type, 0.5, {0.0, 1.0}, false}});
}

SimulationOptions tight() {
  SimulationOptions o;
  o.duration_s = 3.0;
  o.output_step_s = 0.01;
  o.integrator.rtol = 1e-11;
  o.integrator.atol = 1e-13;
  o.integrator.method = IntegratorOptions::Method::Adams;
  return o;
}

/// Rigid coordinates and the elastic deflection at both tips over time.
Eigen::MatrixXd observed(const FlexibleBody& body, const SimulationResult& r) {
  const Eigen::RowVectorXd left = body.basis().evaluate(body.beam().x_left()).phi;
  const Eigen::RowVectorXd right = body.basis().evaluate(body.beam().x_right()).phi;
  Eigen::MatrixXd y(r.t.size(), 5);
  y.leftCols(3) = r.z.leftCols(3);
  y.col(3) = r.z.rightCols(body.n()) * left.transpose();
  y.col(4) = r.z.rightCols(body.n()) * right.transpose();
  return y;
}

struct Differences {
  double rigid = 0.0, tips = 0.0;  // max over time, relative to the paper basis's largest value
};

/// The perturbation solutions (linear in q, no sensitivity to round-off) of the paper's
/// basis and of `other`, both with n functions.
Differences compare(ForceElement::Type type, int n, const BasisOptions& other) {
  const FlexibleBody a = paper_body(type, n, BasisOptions{}), b = paper_body(type, n, other);
  const Excitation ex{{pulse()}};
  const PerturbationResult pa = simulate_perturbation(a, ex, tight()), pb = simulate_perturbation(b, ex, tight());
  REQUIRE(pa.total.ok());
  REQUIRE(pb.total.ok());
  const Eigen::MatrixXd ya = observed(a, pa.total), yb = observed(b, pb.total);
  // the rigid coordinate the load drives: Ry for the force, theta for the moment
  const int driven = type == ForceElement::Type::Force ? 1 : 2;
  Differences d;
  d.rigid = (ya.col(driven) - yb.col(driven)).cwiseAbs().maxCoeff() / ya.col(driven).cwiseAbs().maxCoeff();
  d.tips = (ya.rightCols(2) - yb.rightCols(2)).cwiseAbs().maxCoeff() / ya.rightCols(2).cwiseAbs().maxCoeff();
  return d;
}

BasisOptions fe_basis(FiniteElementOptions::Modes modes, int elements) {
  FiniteElementOptions o{elements, 5};
  o.modes = modes;
  return {BasisOptions::Kind::FiniteElement, o};
}

}  // namespace

TEST_CASE("uniform beam: FE modes clamped at o give the paper's forced responses at equal mode counts",
          "[sim][paper]") {
  // 80 quintic elements: the response's difference falls as h^8 (moment, n = 12: 1.3e-5 at
  // 40 elements, 5.7e-8 at 80, 6.2e-9 at 160, there near the integrator's rtol of 1e-11)
  const BasisOptions clamped = fe_basis(FiniteElementOptions::Modes::ClampedAtReference, 80);
  for (const auto type : {ForceElement::Type::Force, ForceElement::Type::Torque})
    for (const int n : {6, 12}) {
      const Differences d = compare(type, n, clamped);
      INFO((type == ForceElement::Type::Force ? "force" : "moment")
           << " example, n = " << n << std::setprecision(3) << ": rigid " << d.rigid << ", tips " << d.tips);
      // issue 15's 1e-6: both bases span the same functions up to the element discretization
      // (measured at 80 elements: moment 5.7e-8 tips, 3.3e-9 rigid; force 4.3e-9 at 40)
      CHECK(d.rigid <= 1e-6);
      CHECK(d.tips <= 1e-6);
    }
}

TEST_CASE("uniform beam: free-free FE modes converge slowly to the paper's forced responses", "[sim][paper]") {
  // The free-free modes (rigid part at o removed) have continuous curvature and shear at o,
  // where a moment or force at o makes the response's curvature or shear jump: they span
  // another space and converge to it only slowly (docs/theory.md section 4b). Measured
  // relative differences in the tip deflections: force 2.8e-3 -> 3.5e-4, moment 0.27 ->
  // 0.069; in the rigid motion: force 2.0e-4 -> 1.6e-5, moment 1.6e-2 -> 4.2e-3.
  const BasisOptions free_free = fe_basis(FiniteElementOptions::Modes::FreeFree, 40);
  for (const auto type : {ForceElement::Type::Force, ForceElement::Type::Torque}) {
    const bool force = type == ForceElement::Type::Force;
    const Differences d12 = compare(type, 12, free_free), d24 = compare(type, 24, free_free);
    INFO((force ? "force" : "moment") << " example" << std::setprecision(3) << ": n = 12 rigid " << d12.rigid
                                      << ", tips " << d12.tips << "; n = 24 rigid " << d24.rigid << ", tips "
                                      << d24.tips);
    // halving h = 1/n cuts the difference by 8 (force) and 4 (moment): at least 3
    CHECK(d24.tips < d12.tips / 3.0);
    CHECK(d24.rigid < d12.rigid / 3.0);
    // and it is far from issue 15's 1e-6 (this is why the clamped modes exist)
    CHECK(d24.tips > 1e-5);
    if (force) {  // the force example is close already (measured 3.5e-4 and 1.6e-5 at n = 24)
      CHECK(d24.tips < 1e-3);
      CHECK(d24.rigid < 1e-4);
    }
  }
}

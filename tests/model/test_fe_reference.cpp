// Independent reference for a NON-UNIFORM free-free beam with a hub and point masses:
//  * m, S_o, I_o against closed forms written out here (parallel-axis form, not the
//    (b^3 - a^3)/3 form freeflex uses);
//  * Phi_bar, Phi_tilde, M, K against a Gauss-Legendre quadrature implemented here
//    (own Newton-on-Legendre nodes, own panel splitting), using only basis.value/curvature;
//  * elastic frequencies against an Euler-Bernoulli finite-element model written here
//    (Hermite cubic elements, consistent mass, point masses lumped at nodes, hub mass and
//    rotary inertia on the translation/slope DOFs of the node at o).
//
// Convergence facts the frequency tolerances rest on (measured while writing this file):
//  * FE with nodes at every segment junction, at o and at every point mass: the exact mode
//    is smooth on each element, so frequencies converge as h^4; 120 -> 240 elements moves
//    them by <= 1.2e-7 (relative), so the 240-element values are within ~1e-8 of exact.
//  * freeflex's basis is smooth on each side of o, but where EI jumps the exact mode's
//    curvature jumps, so the Ritz error decays only as ~1/NOA (err * NOA within ~10% over
//    NOA = 20..80 for modes 1-3, faster for some higher modes): at NOA = 40 it is
//    1.5e-4 .. 1.3e-3 relative. With EI uniform and only the mass stepped (curvature
//    continuous) it decays as ~NOA^-3: <= 2e-5 at NOA = 40.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/analysis/free_vibration.hpp"
#include "freeflex/model/basis.hpp"
#include "freeflex/model/beam.hpp"
#include "freeflex/model/modal_integrals.hpp"

using namespace freeflex;

namespace {

const double kPi = 3.14159265358979323846;

// L = 1.2 m in three segments; hub at o; a 0.2 kg tip payload and a 0.05 kg mass at s = 0.3.
BeamProperties stepped_beam() {
  BeamProperties p;
  p.segments = {{0.4, 0.6, 3.0}, {0.5, 0.4, 2.0}, {0.3, 0.25, 1.2}};
  p.hub_mass_kg = 0.3;
  p.hub_rotary_inertia_kgm2 = 0.01;
  p.point_masses = {{1.2, 0.2}, {0.3, 0.05}};
  return p;
}

double total_length(const BeamProperties& p) {
  double L = 0.0;
  for (const auto& seg : p.segments) L += seg.length_m;
  return L;
}

// Key positions s (from the left end): ends, segment junctions, o, point masses; ascending, unique.
std::vector<double> key_points(const BeamProperties& p, double s_o) {
  const double L = total_length(p);
  std::vector<double> k{0.0, s_o};
  double s = 0.0;
  for (const auto& seg : p.segments) k.push_back(s += seg.length_m);
  for (const auto& pm : p.point_masses) k.push_back(pm.position_m);
  std::sort(k.begin(), k.end());
  // one position reached by two sums of lengths: equal up to their round-off
  k.erase(std::unique(k.begin(), k.end(), [&](double a, double b) { return std::abs(a - b) < 1e-12 * L; }),
          k.end());
  return k;
}

// Segment containing the open interval around s_mid (s_mid strictly inside a key interval).
const BeamSegment& segment_containing(const BeamProperties& p, double s_mid) {
  double end = 0.0;
  for (const auto& seg : p.segments) {
    end += seg.length_m;
    if (s_mid < end) return seg;
  }
  return p.segments.back();
}

// n-point Gauss-Legendre on [-1, 1] by Newton iteration on P_n (independent of freeflex).
struct Rule {
  std::vector<double> x, w;
};
Rule gauss_legendre_rule(int n) {
  Rule r{std::vector<double>(n), std::vector<double>(n)};
  for (int i = 0; i < n; ++i) {
    double z = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 0.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    r.x[i] = z;
    r.w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
  }
  return r;
}

struct RefIntegrals {
  Eigen::MatrixXd M, K;
  Eigen::RowVectorXd Phi_bar, Phi_tilde;
};

// Modal integrals by own composite 16-point Gauss, panels split at junctions and o, panel
// width <= 1 / (bound on the largest wavenumber): cantilever roots satisfy lambda_k < k pi.
RefIntegrals reference_integrals(const BeamProperties& p, double s_o, const AdmissibleBasis& basis) {
  const int n = basis.size();
  const double L = total_length(p);
  const double kmax = ((n + 1) / 2) * kPi / std::min(s_o, L - s_o);
  const Rule g = gauss_legendre_rule(16);
  RefIntegrals r{Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n), Eigen::RowVectorXd::Zero(n),
                 Eigen::RowVectorXd::Zero(n)};
  std::vector<double> cuts{0.0, s_o};
  double s = 0.0;
  for (const auto& seg : p.segments) cuts.push_back(s += seg.length_m);
  std::sort(cuts.begin(), cuts.end());
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double a = cuts[i], b = cuts[i + 1];
    if (!(b - a > 1e-12 * L)) continue;  // a cut repeated up to round-off of sums of lengths: no interval
    const BeamSegment& seg = segment_containing(p, 0.5 * (a + b));
    const int panels = static_cast<int>(std::ceil((b - a) * kmax));
    const double h = (b - a) / panels;
    for (int k = 0; k < panels; ++k) {
      for (std::size_t q = 0; q < g.x.size(); ++q) {
        const double sq = a + h * (k + 0.5 * (1.0 + g.x[q])), wq = 0.5 * h * g.w[q];
        const double x = sq - s_o;
        const Eigen::RowVectorXd phi = basis.value(x), dd = basis.curvature(x);
        const double dm = wq * seg.mass_per_length_kg_m;
        r.M += dm * phi.transpose() * phi;
        r.Phi_bar += dm * phi;
        r.Phi_tilde += (dm * x) * phi;
        r.K += (wq * seg.bending_stiffness_Nm2) * dd.transpose() * dd;
      }
    }
  }
  for (const auto& pm : p.point_masses) {
    const double x = pm.position_m - s_o;
    const Eigen::RowVectorXd phi = basis.value(x);
    r.M += pm.mass_kg * phi.transpose() * phi;
    r.Phi_bar += pm.mass_kg * phi;
    r.Phi_tilde += (pm.mass_kg * x) * phi;
  }
  return r;  // the hub sits at x = 0 where Phi = 0 (checked separately)
}

struct FeResult {
  Eigen::VectorXd omega;     // elastic natural frequencies, ascending [rad/s]
  Eigen::Vector2d rigid;     // the two rigid eigenvalues omega^2 (round-off) [rad^2/s^2]
  double first_elastic = 0;  // omega^2 of the first elastic mode
};

// Hermite-cubic FE of the free-free beam: DOFs (w, w') per node. Each key interval gets
// refine * ceil(len / L * base) equal elements, so refine = 2 halves every element.
FeResult fe_frequencies(const BeamProperties& p, double s_o, int base, int refine, int count) {
  const double L = total_length(p);
  const std::vector<double> keys = key_points(p, s_o);
  std::vector<double> nodes{keys.front()};
  for (std::size_t i = 0; i + 1 < keys.size(); ++i) {
    const double a = keys[i], b = keys[i + 1];
    const int ne = refine * std::max(1, static_cast<int>(std::ceil((b - a) / L * base)));
    for (int e = 1; e < ne; ++e) nodes.push_back(a + (b - a) * e / ne);
    nodes.push_back(b);
  }
  const int nn = static_cast<int>(nodes.size()), nd = 2 * nn;
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(nd, nd), M = Eigen::MatrixXd::Zero(nd, nd);
  for (int e = 0; e + 1 < nn; ++e) {
    const double l = nodes[e + 1] - nodes[e];
    const BeamSegment& seg = segment_containing(p, 0.5 * (nodes[e] + nodes[e + 1]));
    Eigen::Matrix4d ke, me;
    ke << 12, 6 * l, -12, 6 * l,  //
        6 * l, 4 * l * l, -6 * l, 2 * l * l,  //
        -12, -6 * l, 12, -6 * l,  //
        6 * l, 2 * l * l, -6 * l, 4 * l * l;
    me << 156, 22 * l, 54, -13 * l,  //
        22 * l, 4 * l * l, 13 * l, -3 * l * l,  //
        54, 13 * l, 156, -22 * l,  //
        -13 * l, -3 * l * l, -22 * l, 4 * l * l;
    K.block<4, 4>(2 * e, 2 * e) += (seg.bending_stiffness_Nm2 / (l * l * l)) * ke;
    M.block<4, 4>(2 * e, 2 * e) += (seg.mass_per_length_kg_m * l / 420.0) * me;
  }
  auto node_at = [&](double s) {
    const auto it = std::min_element(nodes.begin(), nodes.end(),
                                     [&](double a, double b) { return std::abs(a - s) < std::abs(b - s); });
    REQUIRE(std::abs(*it - s) < 1e-12 * L);  // every mass sits exactly on a node
    return static_cast<int>(it - nodes.begin());
  };
  for (const auto& pm : p.point_masses) {
    const int k = node_at(pm.position_m);
    M(2 * k, 2 * k) += pm.mass_kg;
  }
  const int io = node_at(s_o);
  M(2 * io, 2 * io) += p.hub_mass_kg;
  M(2 * io + 1, 2 * io + 1) += p.hub_rotary_inertia_kgm2;

  // Shift-invert form M v = nu (K + sigma M) v, lambda = 1/nu - sigma: solving K v = lambda M v
  // directly loses the low lambdas to eps * lambda_max (measured 2e-6 .. 1e-4 relative at
  // 400 .. 800 elements); this form keeps them. sigma ~ the first free-free eigenvalue scale.
  double EI_mean = 0.0, mu_mean = 0.0;
  for (const auto& seg : p.segments) {
    EI_mean += seg.bending_stiffness_Nm2 * seg.length_m / L;
    mu_mean += seg.mass_per_length_kg_m * seg.length_m / L;
  }
  const double sigma = 500.0 * EI_mean / (mu_mean * std::pow(L, 4));
  const Eigen::MatrixXd B = K + sigma * M;
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(M, B, Eigen::EigenvaluesOnly | Eigen::Ax_lBx);
  REQUIRE(es.info() == Eigen::Success);
  const Eigen::VectorXd nu = es.eigenvalues().reverse();  // largest nu = smallest lambda first
  const Eigen::VectorXd lambda = nu.cwiseInverse().array() - sigma;
  FeResult r;
  r.rigid = lambda.head<2>();
  r.first_elastic = lambda(2);
  r.omega = lambda.segment(2, count).cwiseMax(0.0).cwiseSqrt();
  return r;
}

Eigen::VectorXd freeflex_omega(const Beam& beam, int noa, int count) {
  return free_vibration(modal_integrals(beam, make_basis(beam, noa))).omega.head(count);
}

}  // namespace

TEST_CASE("stepped beam with hub and payloads: m, S_o, I_o match closed forms", "[model]") {
  const BeamProperties p = stepped_beam();
  // By hand: distributed 0.24 + 0.2 + 0.075, point masses 0.25, hub 0.3.
  const double m_hand = 1.065;
  // Mass centre of distributed and point masses (the hub sits at o):
  // (0.24*0.2 + 0.2*0.65 + 0.075*1.05 + 0.2*1.2 + 0.05*0.3) / 0.765.
  const double s_c_hand = 0.51175 / 0.765;
  for (const bool explicit_ref : {false, true}) {
    BeamProperties q = p;
    if (explicit_ref) q.reference_m = 0.45;  // off the mass centre: S_o != 0
    const Beam beam(q);
    const double s_o = explicit_ref ? 0.45 : s_c_hand;
    INFO("explicit reference: " << explicit_ref);
    // the default reference is the mass centre: round-off of a 5-term quotient
    CHECK(std::abs(beam.reference_s() - s_o) <= 1e-15 * 1.2 * 4);
    const ModalIntegrals mi = modal_integrals(beam, make_basis(beam, 30));
    // Parallel-axis closed forms about o, from the segment centres.
    double m = q.hub_mass_kg, S = 0.0, I = q.hub_rotary_inertia_kgm2, s = 0.0;
    for (const auto& seg : q.segments) {
      const double ms = seg.mass_per_length_kg_m * seg.length_m, c = s + 0.5 * seg.length_m - s_o;
      m += ms;
      S += ms * c;
      I += ms * (seg.length_m * seg.length_m / 12.0 + c * c);
      s += seg.length_m;
    }
    for (const auto& pm : q.point_masses) {
      const double x = pm.position_m - s_o;
      m += pm.mass_kg;
      S += pm.mass_kg * x;
      I += pm.mass_kg * x * x;
    }
    INFO(std::setprecision(16) << "freeflex m, S_o, I_o = " << mi.m << ", " << mi.S_o << ", " << mi.I_o
                               << "; reference " << m << ", " << S << ", " << I);
    CHECK(std::abs(m - m_hand) <= 1e-15 * m_hand * 4);  // the by-hand sum, few-term round-off
    // closed forms summed in a different order: a few ulp of the largest term
    CHECK(std::abs(mi.m - m) <= 1e-13 * m);
    CHECK(std::abs(mi.S_o - S) <= 1e-13 * m * 1.2);  // absolute: at the mass centre S_o = 0
    CHECK(std::abs(mi.I_o - I) <= 1e-13 * I);
    if (explicit_ref) CHECK(std::abs(mi.S_o) > 0.1);  // S_o = 0.765 * (0.66895 - 0.45) = 0.1675 kg m
  }
}

TEST_CASE("stepped beam with hub and payloads: Phi_bar, Phi_tilde, M, K match an independent quadrature",
          "[model]") {
  const BeamProperties p = stepped_beam();
  const int noa = 40;
  for (const bool explicit_ref : {false, true}) {
    BeamProperties q = p;
    if (explicit_ref) q.reference_m = 0.45;
    const Beam beam(q);
    INFO("explicit reference: " << explicit_ref);
    const AdmissibleBasis basis = make_basis(beam, noa);
    // The hub contributes nothing to Phi_bar, Phi_tilde, M because Phi(0) = 0 (and Phi'(0) = 0
    // makes the hub rotary inertia purely rigid): closed-form evaluation, round-off only.
    CHECK(basis.value(0.0).cwiseAbs().maxCoeff() < 1e-13);
    CHECK(basis.slope(0.0).cwiseAbs().maxCoeff() * beam.length() < 1e-12);
    const ModalIntegrals mi = modal_integrals(beam, basis);
    const RefIntegrals ref = reference_integrals(q, beam.reference_s(), basis);
    const double m = mi.m, Lx = beam.length();
    const double dPb = (mi.Phi_bar - ref.Phi_bar).cwiseAbs().maxCoeff();
    const double dPt = (mi.Phi_tilde - ref.Phi_tilde).cwiseAbs().maxCoeff();
    const double dM = (mi.M - ref.M).cwiseAbs().maxCoeff();
    // K entries span ~6 decades across NOA = 40: compare relative to sqrt(K_ii K_jj).
    const Eigen::VectorXd kd = ref.K.diagonal().cwiseSqrt();
    const double dK = ((mi.K - ref.K).array() / (kd * kd.transpose()).array()).abs().maxCoeff();
    INFO(std::setprecision(3) << "max |diff|: Phi_bar " << dPb << " kg, Phi_tilde " << dPt << " kg m, M "
                              << dM << " kg, K (scaled) " << dK);
    // Both are quadratures exact to round-off (thousands of O(m) terms; measured <= 2.3e-15):
    // 1e-13 of m (times L for Phi_tilde).
    CHECK(dPb <= 1e-13 * m);
    CHECK(dPt <= 1e-13 * m * Lx);
    CHECK(dM <= 1e-13 * m);
    // Same for K, scaled entrywise (measured <= 4.7e-15); the diagonal is positive.
    CHECK(dK <= 1e-13);
    CHECK(ref.K.diagonal().minCoeff() > 0.0);
  }
}

TEST_CASE("stepped beam with hub and payloads: elastic frequencies vs Hermite finite elements",
          "[analysis]") {
  const BeamProperties p = stepped_beam();
  const int count = 5;
  for (const bool explicit_ref : {false, true}) {
    BeamProperties q = p;
    if (explicit_ref) q.reference_m = 0.45;
    const Beam beam(q);
    INFO("explicit reference: " << explicit_ref);
    const FeResult fe1 = fe_frequencies(q, beam.reference_s(), 120, 1, count);
    const FeResult fe = fe_frequencies(q, beam.reference_s(), 120, 2, count);
    // FE rigid modes: zero to the round-off of the shift-invert solve (measured <= 4e-8 of
    // the first elastic eigenvalue at 240 elements).
    {
      INFO("FE rigid omega^2 " << fe.rigid.transpose() << ", first elastic " << fe.first_elastic);
      CHECK(fe.rigid.cwiseAbs().maxCoeff() <= 1e-6 * fe.first_elastic);
    }
    const Eigen::VectorXd w20 = freeflex_omega(beam, 20, count);
    const Eigen::VectorXd w30 = freeflex_omega(beam, 30, count);
    const Eigen::VectorXd w40 = freeflex_omega(beam, 40, count);
    for (int i = 0; i < count; ++i) {
      INFO(std::setprecision(12) << "elastic mode " << i + 1 << ": FE(120) " << fe1.omega(i) << ", FE(240) "
                                 << fe.omega(i) << ", freeflex NOA 20/30/40 " << w20(i) << " / " << w30(i)
                                 << " / " << w40(i) << " rad/s; NOA-40 relative error "
                                 << std::setprecision(3) << w40(i) / fe.omega(i) - 1
                                 << ", (w40 - FE) / (w20 - w40) "
                                 << (w40(i) - fe.omega(i)) / (w20(i) - w40(i)));
      // FE h^4 convergence: 120 -> 240 elements moved <= 1.2e-7, so FE(240) is ~1e-8 from exact.
      CHECK(std::abs(fe1.omega(i) / fe.omega(i) - 1) <= 1e-6);
      // Nested Ritz spaces: freeflex frequencies must fall monotonically with NOA.
      CHECK(w30(i) < w20(i));
      CHECK(w40(i) < w30(i));
      // Both are upper bounds of the exact value and FE(240) is ~1e-8 above it: freeflex
      // may not fall below FE by more than that.
      CHECK(w40(i) >= fe.omega(i) * (1 - 1e-6));
      // NOA-40 error is O(1/NOA) from the EI jumps: measured 1.5e-4 .. 1.3e-3 relative.
      CHECK(w40(i) <= fe.omega(i) * (1 + 2e-3));
      // The error must be what the 1/NOA convergence predicts: err(40) ~ w20 - w40 (measured
      // ratio 0.28 .. 1.12); a bias of more than ~half the NOA-40 error fails this.
      CHECK(w40(i) - fe.omega(i) <= 1.5 * (w20(i) - w40(i)));
    }
  }
}

TEST_CASE("stepped mass, uniform EI, hub and payloads: freeflex frequencies match FE tightly", "[analysis]") {
  // Curvature is continuous when EI is uniform, so freeflex converges fast (~NOA^-3) and the
  // mass, hub and payload handling is tested far below the 1/NOA floor of the stepped-EI case.
  BeamProperties q = stepped_beam();
  for (auto& seg : q.segments) seg.bending_stiffness_Nm2 = 2.0;
  const Beam beam(q);
  const int count = 5;
  const FeResult fe1 = fe_frequencies(q, beam.reference_s(), 120, 1, count);
  const FeResult fe = fe_frequencies(q, beam.reference_s(), 120, 2, count);
  {
    INFO("FE rigid omega^2 " << fe.rigid.transpose() << ", first elastic " << fe.first_elastic);
    CHECK(fe.rigid.cwiseAbs().maxCoeff() <= 1e-6 * fe.first_elastic);  // round-off, see above
  }
  const Eigen::VectorXd w20 = freeflex_omega(beam, 20, count);
  const Eigen::VectorXd w40 = freeflex_omega(beam, 40, count);
  for (int i = 0; i < count; ++i) {
    INFO(std::setprecision(12) << "elastic mode " << i + 1 << ": FE(120) " << fe1.omega(i) << ", FE(240) "
                               << fe.omega(i) << ", freeflex NOA 20/40 " << w20(i) << " / " << w40(i)
                               << " rad/s; NOA-40 relative error " << std::setprecision(3)
                               << w40(i) / fe.omega(i) - 1 << ", (w40 - FE) / (w20 - w40) "
                               << (w40(i) - fe.omega(i)) / (w20(i) - w40(i)));
    CHECK(std::abs(fe1.omega(i) / fe.omega(i) - 1) <= 1e-6);  // FE h^4 convergence, as above
    CHECK(w40(i) >= fe.omega(i) * (1 - 1e-6));                // both upper bounds, FE error ~1e-8
    // NOA-40 error measured <= 1.9e-5 (mode 4), 6e-7 .. 2.1e-6 for the others.
    CHECK(w40(i) <= fe.omega(i) * (1 + 5e-5));
    // ~NOA^-3 convergence: err(40) ~ (w20 - w40) / 7 (measured 1/11.5 .. 1/6.9).
    CHECK(w40(i) - fe.omega(i) <= 0.3 * (w20(i) - w40(i)));
  }
}

// Geometric stiffening integrals (docs/theory.md section 13): the foreshortening matrix
// H(x) of the bent beam and its mass integrals H_bar and G_c, by composite Gauss
// quadrature through the basis's evaluate() alone (so any basis serves).
#include <algorithm>
#include <cmath>
#include <vector>

#include "freeflex/model/modal_integrals.hpp"

namespace freeflex {
namespace {

constexpr int kPoints = 20;  // as beam_quadrature: with panels no wider than 2.5 / kmax

/// Composite Gauss rule on [a, b] cut at every point of `cuts` inside it, panels no wider
/// than 2.5 / kmax (the density beam_quadrature uses, which resolves products of basis
/// functions to round-off).
GaussRule rule_between(double a, double b, std::vector<double> cuts, double kmax) {
  cuts.push_back(a);
  cuts.push_back(b);
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  std::vector<double> nodes, weights;
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double lo = cuts[i], hi = cuts[i + 1];
    if (lo < a || hi > b || !(hi > lo)) continue;
    const int panels = std::max(1, static_cast<int>(std::ceil((hi - lo) * kmax / 2.5)));
    const GaussRule g = composite_gauss(lo, hi, panels, kPoints);
    nodes.insert(nodes.end(), g.nodes.data(), g.nodes.data() + g.nodes.size());
    weights.insert(weights.end(), g.weights.data(), g.weights.data() + g.weights.size());
  }
  GaussRule r;
  r.nodes = Eigen::Map<const Eigen::VectorXd>(nodes.data(), static_cast<Eigen::Index>(nodes.size()));
  r.weights = Eigen::Map<const Eigen::VectorXd>(weights.data(), static_cast<Eigen::Index>(weights.size()));
  return r;
}

/// Where the integrands may kink: o, the ends and the segment junctions.
std::vector<double> cuts_of(const Beam& beam) {
  std::vector<double> c = beam.breakpoints_x();
  c.push_back(0.0);
  return c;
}

/// Distributed mass beyond ξ (away from o) and its first absolute moment (eq. 13.3):
/// μ(ξ) = ∫ dm and σ(ξ) = ∫ |x| dm over the distributed mass at |x| > |ξ| on ξ's side.
void beyond(const Beam& beam, double xi, double& mu, double& sigma) {
  mu = sigma = 0.0;
  const std::vector<double> ends = beam.breakpoints_x();
  const auto& segs = beam.properties().segments;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const double a = ends[i], b = ends[i + 1], rho = segs[i].mass_per_length_kg_m;
    if (xi >= 0.0) {
      const double lo = std::max(a, xi);
      if (b > lo) {
        mu += rho * (b - lo);
        sigma += rho * (b - lo) * (b + lo) / 2.0;
      }
    } else {
      const double hi = std::min(b, xi);
      if (hi > a) {
        mu += rho * (hi - a);
        sigma += rho * (hi - a) * -(hi + a) / 2.0;  // ∫_a^hi (-x) dx
      }
    }
  }
}

}  // namespace

Eigen::MatrixXd foreshortening_matrix(const Beam& beam, const AdmissibleBasis& basis, double x) {
  const int n = basis.size();
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  if (x == 0.0) return H;
  const GaussRule g = rule_between(std::min(0.0, x), std::max(0.0, x), cuts_of(beam), basis.max_wavenumber());
  for (int i = 0; i < g.nodes.size(); ++i) {
    const Eigen::RowVectorXd d = basis.evaluate(g.nodes(i)).dphi;
    H.noalias() += g.weights(i) * d.transpose() * d;
  }
  return 0.5 * (H + H.transpose());
}

StiffeningIntegrals stiffening_integrals(const Beam& beam, const AdmissibleBasis& basis) {
  const int n = basis.size();
  StiffeningIntegrals s{Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n)};
  // Distributed mass, the order of integration exchanged (eq. 13.3).
  const GaussRule g = rule_between(beam.x_left(), beam.x_right(), cuts_of(beam), basis.max_wavenumber());
  for (int i = 0; i < g.nodes.size(); ++i) {
    const double xi = g.nodes(i);
    double mu = 0.0, sigma = 0.0;
    beyond(beam, xi, mu, sigma);
    const Eigen::RowVectorXd d = basis.evaluate(xi).dphi;
    const Eigen::MatrixXd F = d.transpose() * d;
    s.H_bar.noalias() += (g.weights(i) * (xi >= 0.0 ? mu : -mu)) * F;
    s.G_c.noalias() += (g.weights(i) * sigma) * F;
  }
  // Point masses by the definition: m sgn(x) H(x) and m |x| H(x). The hub sits at o (H = 0).
  for (const auto& pm : beam.properties().point_masses) {
    const double x = beam.x_of(pm.position_m);
    if (x == 0.0 || pm.mass_kg == 0.0) continue;
    const Eigen::MatrixXd H = foreshortening_matrix(beam, basis, x);
    s.H_bar += (x > 0.0 ? pm.mass_kg : -pm.mass_kg) * H;
    s.G_c += (pm.mass_kg * std::abs(x)) * H;
  }
  s.H_bar = 0.5 * (s.H_bar + s.H_bar.transpose()).eval();
  s.G_c = 0.5 * (s.G_c + s.G_c.transpose()).eval();
  return s;
}

ModalIntegrals stiffened_modal_integrals(const Beam& beam, const AdmissibleBasis& basis) {
  ModalIntegrals mi = modal_integrals(beam, basis);
  StiffeningIntegrals s = stiffening_integrals(beam, basis);
  mi.H_bar = std::move(s.H_bar);
  mi.G_c = std::move(s.G_c);
  return mi;
}

}  // namespace freeflex

// Geometric stiffening integrals (docs/theory.md section 14): the foreshortening matrix
// H(x) of the bent beam and its mass integrals H_bar and G_c, by composite Gauss
// quadrature through the ShapeBasis interface alone (evaluate(), cuts(), max_panel_width()),
// so the paper's basis and the finite-element basis serve alike.
#include <algorithm>
#include <cmath>
#include <vector>

#include "freeflex/model/modal_integrals.hpp"
#include "model/beam_rule.hpp"

namespace freeflex {
namespace {

/// Distributed mass beyond ξ (away from o) and its first absolute moment (eq. 14.3):
/// μ(ξ) = ∫ dm and σ(ξ) = ∫ |x| dm over the distributed mass at |x| > |ξ| on ξ's side.
void beyond(const Beam& beam, double xi, double& mu, double& sigma) {
  mu = sigma = 0.0;
  const std::vector<double> ends = beam.breakpoints_x();
  const auto& segs = beam.properties().segments;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const double a = ends[i], b = ends[i + 1], rho = segs[i].mass_per_length_kg_m;
    if (const auto& rho_b = segs[i].mass_per_length_end_kg_m) {
      // mass varying linearly from rho at a to rho_b at b (eq. 3.4): on [lo, hi] inside
      // the segment, ∫ dm = h (r_lo + r_hi) / 2 and ∫ x dm = h (r_lo (2 lo + hi) + r_hi (lo + 2 hi)) / 6
      const double lo = xi >= 0.0 ? std::max(a, xi) : a, hi = xi >= 0.0 ? b : std::min(b, xi);
      if (!(hi > lo)) continue;
      const double h = hi - lo, slope = (*rho_b - rho) / (b - a);
      const double r_lo = rho + slope * (lo - a), r_hi = rho + slope * (hi - a);
      const double first = h * (r_lo * (2.0 * lo + hi) + r_hi * (lo + 2.0 * hi)) / 6.0;
      mu += 0.5 * h * (r_lo + r_hi);
      sigma += xi >= 0.0 ? first : -first;
      continue;
    }
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

Eigen::MatrixXd foreshortening_matrix(const Beam& beam, const ShapeBasis& basis, double x) {
  const int n = basis.size();
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  if (x == 0.0) return H;
  const GaussRule g = detail::beam_rule(beam, basis, std::min(0.0, x), std::max(0.0, x), 0.0);
  for (int i = 0; i < g.nodes.size(); ++i) {
    const Eigen::RowVectorXd d = basis.evaluate(g.nodes(i)).dphi;
    H.noalias() += g.weights(i) * d.transpose() * d;
  }
  return 0.5 * (H + H.transpose());
}

StiffeningIntegrals stiffening_integrals(const Beam& beam, const ShapeBasis& basis) {
  const int n = basis.size();
  StiffeningIntegrals s{Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n)};
  // Distributed mass, the order of integration exchanged (eq. 14.3).
  // the modal integrals' rule, cut at o as well (where |x| and μ(ξ) kink)
  const GaussRule g = detail::beam_rule(beam, basis, beam.x_left(), beam.x_right(), 0.0);
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

ModalIntegrals stiffened_modal_integrals(const Beam& beam, const ShapeBasis& basis) {
  ModalIntegrals mi = modal_integrals(beam, basis);
  StiffeningIntegrals s = stiffening_integrals(beam, basis);
  mi.H_bar = std::move(s.H_bar);
  mi.G_c = std::move(s.G_c);
  return mi;
}

}  // namespace freeflex

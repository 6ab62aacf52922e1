// The modal integrals of the discretized beam (m, S_o, I_o, M, K, Φ̄, Φ̃) by composite
// Gauss quadrature.
#include "freeflex/model/modal_integrals.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "model/beam_rule.hpp"

namespace freeflex {

AdmissibleBasis make_basis(const Beam& beam, int noa) {
  return AdmissibleBasis(noa, -beam.x_left(), beam.x_right());
}

std::shared_ptr<const ShapeBasis> make_basis(const Beam& beam, int n, const BasisOptions& options) {
  if (options.kind == BasisOptions::Kind::FiniteElement)
    return std::make_shared<const FiniteElementBasis>(beam, n, options.finite_element);
  return std::make_shared<const AdmissibleBasis>(make_basis(beam, n));
}

namespace detail {

GaussRule beam_rule(const Beam& beam, const ShapeBasis& basis, double a, double b, double extra_cut) {
  constexpr int kPoints = 20;
  // 20-point Gauss is exact to degree 39: for the paper's basis, panels of width
  // 2.5 / kmax resolve the products (wavenumber up to 2 kmax) far below round-off; for
  // the finite-element basis each element is one polynomial panel.
  const double width = basis.max_panel_width();
  std::vector<double> cuts{a, b};
  auto inside = [&](double c) { return c > a && c < b; };
  for (double c : beam.breakpoints_x())
    if (inside(c)) cuts.push_back(c);
  for (double c : basis.cuts())
    if (inside(c)) cuts.push_back(c);
  if (inside(extra_cut)) cuts.push_back(extra_cut);
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  std::vector<GaussRule> parts;
  int total = 0;
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double lo = cuts[i], hi = cuts[i + 1];
    if (!(hi > lo)) continue;
    const int panels = std::max(1, static_cast<int>(std::ceil((hi - lo) / width)));
    parts.push_back(composite_gauss(lo, hi, panels, kPoints));
    total += static_cast<int>(parts.back().nodes.size());
  }
  GaussRule r{Eigen::VectorXd(total), Eigen::VectorXd(total)};
  int at = 0;
  for (const auto& p : parts) {
    r.nodes.segment(at, p.nodes.size()) = p.nodes;
    r.weights.segment(at, p.nodes.size()) = p.weights;
    at += static_cast<int>(p.nodes.size());
  }
  return r;
}

}  // namespace detail

GaussRule beam_quadrature(const Beam& beam, const ShapeBasis& basis) {
  return detail::beam_rule(beam, basis, beam.x_left(), beam.x_right(), beam.x_left());
}

ModalIntegrals modal_integrals(const Beam& beam, const ShapeBasis& basis) {
  const int n = basis.size();
  ModalIntegrals mi;
  mi.M.setZero(n, n);
  mi.K.setZero(n, n);
  mi.Phi_bar.setZero(n);
  mi.Phi_tilde.setZero(n);
  mi.H_bar.setZero(n, n);  // filled only when a model asks for geometric stiffening
  mi.G_c.setZero(n, n);

  // Elastic integrals by quadrature; the rigid ones (m, S_o, I_o) in closed form below.
  auto add_mass = [&](double x, double dm, const Eigen::RowVectorXd& phi) {
    mi.M.noalias() += dm * phi.transpose() * phi;
    mi.Phi_bar += dm * phi;
    mi.Phi_tilde += (x * dm) * phi;
  };

  const GaussRule q = beam_quadrature(beam, basis);
  for (int i = 0; i < q.nodes.size(); ++i) {
    const double x = q.nodes(i), w = q.weights(i);
    const BasisValues v = basis.evaluate(x);
    add_mass(x, w * beam.mass_per_length(x), v.phi);
    mi.K.noalias() += (w * beam.bending_stiffness(x)) * v.ddphi.transpose() * v.ddphi;
  }
  const auto& p = beam.properties();
  const std::vector<double> ends = beam.breakpoints_x();
  for (std::size_t i = 0; i < p.segments.size(); ++i) {
    const double a = ends[i], b = ends[i + 1], mu = p.segments[i].mass_per_length_kg_m;
    if (const auto& mu_b = p.segments[i].mass_per_length_end_kg_m) {
      // eq. 3.4: mass varying linearly from mu at a to mu_b at b
      const double h = b - a;
      mi.m += 0.5 * h * (mu + *mu_b);
      mi.S_o += h * (mu * (2.0 * a + b) + *mu_b * (a + 2.0 * b)) / 6.0;
      mi.I_o += h * (mu * (3.0 * a * a + 2.0 * a * b + b * b) + *mu_b * (a * a + 2.0 * a * b + 3.0 * b * b)) / 12.0;
      continue;
    }
    mi.m += mu * (b - a);
    mi.S_o += mu * (b - a) * (b + a) / 2.0;
    mi.I_o += mu * (b - a) * (b * b + a * b + a * a) / 3.0;
  }
  for (const auto& pm : p.point_masses) {
    const double x = beam.x_of(pm.position_m);
    mi.m += pm.mass_kg;
    mi.S_o += x * pm.mass_kg;
    mi.I_o += x * x * pm.mass_kg;
    add_mass(x, pm.mass_kg, basis.value(x));
  }
  // The hub sits at o, where Phi = 0: it adds mass and rotary inertia only.
  mi.m += p.hub_mass_kg;
  mi.I_o += p.hub_rotary_inertia_kgm2;
  // Symmetrize: the sums are symmetric in exact arithmetic.
  mi.M = 0.5 * (mi.M + mi.M.transpose()).eval();
  mi.K = 0.5 * (mi.K + mi.K.transpose()).eval();
  return mi;
}

}  // namespace freeflex

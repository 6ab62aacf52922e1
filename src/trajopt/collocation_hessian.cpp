// The Hessian of the collocation NLP's Lagrangian (trajopt/collocation.hpp): the
// dynamics' second derivatives contracted point by point, the compressed form's
// midpoint chain rule, and the objective's terms, into their slots.
#include "freeflex/trajopt/collocation.hpp"

#include <stdexcept>
#include <string>

namespace freeflex {
namespace {

/// The lower triangle of B = Lᵀ R (L, R: k x q). For k <= 4 (the rigid problems) each entry
/// is a dot product of two columns summed in order from zero, the roundings of Eigen's
/// product (in a build without fused multiply-adds, the default) without its set-up, which
/// costs more than the arithmetic there (the rigid slew's whole run 0.8% fewer
/// instructions); for the elastic problems' larger k Eigen's blocked product is faster
/// (2.3% of the elastic slew).
void lower_product(const Eigen::MatrixXd& L, const Eigen::MatrixXd& R, Eigen::MatrixXd& B) {
  const Eigen::Index k = L.rows(), q = L.cols();
  if (k > 4) {
    B.triangularView<Eigen::Lower>() = L.transpose() * R;
    return;
  }
  for (Eigen::Index j = 0; j < q; ++j) {
    const double* r = R.col(j).data();
    for (Eigen::Index i = j; i < q; ++i) {
      const double* l = L.col(i).data();
      double acc = 0.0;
      for (Eigen::Index t = 0; t < k; ++t) acc += l[t] * r[t];
      B(i, j) = acc;
    }
  }
}

}  // namespace


const Eigen::VectorXd& CollocationNlp::hessian_values(Data& data, const Eigen::Ref<const Eigen::VectorXd>& w,
                                                      double obj_factor,
                                                      const Eigen::Ref<const Eigen::VectorXd>& lambda) const {
  if (w.size() != n_ || lambda.size() != m_)
    throw std::invalid_argument("collocation: hessian_values needs w of size " + std::to_string(n_) +
                                " and lambda of size " + std::to_string(m_));
  Data::Cache& c = data.cache;
  Eigen::MatrixXd &lam_eff_ = c.lam_eff, &nu_eff_ = c.nu_eff, &Y_ = c.Y, &B_ = c.B;
  const Eigen::MatrixXd &f_ = c.f, &J_ = c.J, &Jc_ = c.Jc, &xc_ = c.xc;
  Eigen::VectorXd& values = data.hessian;
  values.resize(hessian_nonzeros());
  const int nx = nx_;
  const double T = T_of(w);
  values.setZero();
  // Each point's dynamics enter the defects linearly through h α f_j: collect the
  // multipliers per point, then one second-derivative contraction per point.
  lam_eff_.setZero();
  nu_eff_.setZero();
  for (const Block& bl : blocks_) {
    const double s = sigma_[bl.interval];
    const auto mu = lambda.segment(bl.row, nx);
    for (const Term& tm : bl.terms) {
      if (tm.alpha == 0.0) continue;
      lam_eff_.col(tm.point) -= (s * T * tm.alpha) * mu;
      nu_eff_.col(tm.point) -= (s * tm.alpha) * mu;  // ∂/∂T of the same terms
    }
  }
  if (free_time() || num_mid_controls()) ensure_jac(c, w);
  const auto& hpat = dyn_.hessian_pattern();

  // HS compressed: λᵀd = λᵀ(x_b − x_a) − h/6 λᵀ(f_a + f_b) + s g(y),  s = −4h/6,
  // g = λᵀ f(y), y = (x_c, u_c). ∇²(s g) = s Yᵀ H_c Y + s μᵀ∇²x_c (μ = J_c,xᵀ λ), with
  // ∇²x_c = h/8 (f_a'' − f_b''), plus the terms from s and h depending on T.
  for (int k = 0; k < num_mid_controls(); ++k) {
    const double sg = sigma_[k], h = sg * T, s = -4.0 * h / 6.0, ds = -4.0 * sg / 6.0;
    const auto lam = lambda.segment(nx * k, nx);
    const auto Ja = J_.middleCols(point_offset(k), nz_);
    const auto Jb = J_.middleCols(point_offset(k + 1), nz_);
    const auto Jc = Jc_.middleCols(static_cast<Eigen::Index>(k) * nz_, nz_);
    const Eigen::VectorXd mu = Jc.leftCols(nx).transpose() * lam;
    lam_eff_.col(k) += -(h / 6.0) * lam + (s * h / 8.0) * mu;
    lam_eff_.col(k + 1) += -(h / 6.0) * lam - (s * h / 8.0) * mu;
    // Y = ∂y/∂(z_a, z_b, u_c, T)
    Y_.setZero();
    Y_.topRows(nx).leftCols(nz_) = (h / 8.0) * Ja;
    Y_.topRows(nx).middleCols(nz_, nz_) = (-h / 8.0) * Jb;
    for (int i = 0; i < nx; ++i) {
      Y_(i, i) += 0.5;
      Y_(i, nz_ + i) += 0.5;
    }
    for (int i = 0; i < nu_; ++i) Y_(nx + i, 2 * nz_ + i) = 1.0;
    const int q = static_cast<int>(Y_.cols());
    if (free_time()) Y_.col(q - 1).head(nx) = (sg / 8.0) * (f_.col(k) - f_.col(k + 1));
    Eigen::MatrixXd& Hbuf_ = c.dyn.H;
    dyn_.calc_hessian(c.dyn, xc_.col(k), w.segment(mid_control_offset(k), nu_), lam);
    // H vanishes on h_rest_ x h_rest_ (S = h_cover_, C = h_rest_), so
    // Yᵀ H Y = Y_Sᵀ (H_SS Y_S + K) + Kᵀ Y_S with K = H_SC Y_C: one product Lᵀ R with
    // L = [Y_S; K], R = [H_SS Y_S + K; Y_S], of inner dimension 2|S| (8 for the flexible
    // model, against the 20 rows of H).
    const int ns = static_cast<int>(h_cover_.size()), nr = static_cast<int>(h_rest_.size());
    c.L.resize(2 * ns, q);
    c.R.resize(2 * ns, q);
    c.Yr.resize(nr, q);
    c.Hsr.resize(ns, nr);
    c.Hss.resize(ns, ns);
    for (int i = 0; i < ns; ++i) {
      c.L.row(i) = Y_.row(h_cover_[i]);
      for (int j = 0; j < nr; ++j) c.Hsr(i, j) = s * Hbuf_(h_cover_[i], h_rest_[j]);
      for (int j = 0; j < ns; ++j) c.Hss(i, j) = s * Hbuf_(h_cover_[i], h_cover_[j]);
    }
    for (int i = 0; i < nr; ++i) c.Yr.row(i) = Y_.row(h_rest_[i]);
    if (nr > 0)
      c.L.bottomRows(ns).noalias() = c.Hsr * c.Yr;
    else
      c.L.bottomRows(ns).setZero();
    c.R.topRows(ns) = c.L.bottomRows(ns);
    c.R.topRows(ns).noalias() += c.Hss * c.L.topRows(ns);
    c.R.bottomRows(ns) = c.L.topRows(ns);
    // B is symmetric and only its lower triangle is read (dense_act_ ascends; the T row is last)
    B_.resize(q, q);
    lower_product(c.L, c.R, B_);
    if (free_time()) {
      const int iT = q - 1;
      // s' ∂g/∂v with ∂g/∂v = λᵀ J_c Y; ∂²x_c/∂T∂z_a = σ/8 J_a, ∂²x_c/∂T∂z_b = −σ/8 J_b
      const Eigen::RowVectorXd dg = lam.transpose() * Jc * Y_;
      B_.row(iT).head(2 * nz_ + nu_) += ds * dg.head(2 * nz_ + nu_);
      B_.row(iT).head(nz_) += -(sg / 6.0) * (lam.transpose() * Ja) + (s * sg / 8.0) * (mu.transpose() * Ja);
      B_.row(iT).segment(nz_, nz_) += -(sg / 6.0) * (lam.transpose() * Jb) - (s * sg / 8.0) * (mu.transpose() * Jb);
      B_(iT, iT) += 2.0 * ds * dg(iT);
    }
    int idx = 0;
    for (std::size_t i = 0; i < dense_act_.size(); ++i)
      for (std::size_t j = 0; j <= i; ++j) values(dense_slots_[k][idx++]) += B_(dense_act_[i], dense_act_[j]);
    if (free_time()) {
      idx = 0;
      for (int c : dense_trow_) values(denseT_slots_[k][idx++]) += B_(q - 1, c);
      values(denseT_slots_[k][idx]) += B_(q - 1, q - 1);
    }
  }

  for (int j = 0; j < P_; ++j) {
    const int off = point_offset(j);
    const Eigen::MatrixXd& Hbuf_ = dyn_.calc_hessian(c.dyn, w.segment(off, nx), w.segment(off + nx, nu_), lam_eff_.col(j));
    for (std::size_t e = 0; e < hpat.size(); ++e) values(f_slots_[j][e]) += Hbuf_(hpat[e].first, hpat[e].second);
    if (free_time() && !num_mid_controls()) {
      const auto Jj = J_.middleCols(off, nz_);
      for (int c : fcols_) values(fT_slots_[j][c]) += nu_eff_.col(j).dot(Jj.col(c));
    }
  }
  if (obj_factor == 0.0) return values;
  if (problem_.w_vibration > 0.0) {
    const ElasticDynamics& el = *dyn_.elastic();
    const int n = el.n();
    const double wv = obj_factor * problem_.w_vibration;
    for (std::size_t e = 0; e < vib_slots_.size(); ++e) {
      const int i = vib_ij_[e].first, j = vib_ij_[e].second;
      values(vib_slots_[e]) += wv * (i < n ? el.stiffness()(i, j) : el.condensed_mass()(i - n, j));
    }
  }
  if (problem_.w_energy > 0.0) {
    const double we = obj_factor * problem_.w_energy;
    for (std::size_t cp = 0; cp < ctrl_.size(); ++cp)
      for (int a = 0; a < nu_; ++a) {
        values(energy_slots_[cp][a]) += we * T * ctrl_[cp].qbar * 2.0 * W_(a);
        if (free_time()) values(uT_slots_[cp][a]) += we * ctrl_[cp].qbar * 2.0 * W_(a) * w(ctrl_[cp].offset + a);
      }
  }
  if (problem_.w_smooth > 0.0) {
    const double ws = obj_factor * problem_.w_smooth;
    const int npi = points_per_interval();
    for (int k = 0; k < intervals(); ++k) {
      const double h = sigma_[k] * T;
      for (int act = 0; act < nu_; ++act) {
        const std::vector<int>& sl = smooth_slots_[k * nu_ + act];
        for (std::size_t p = 0; p < sl.size(); ++p)
          values(sl[p]) += ws * 2.0 * Msmooth_(smooth_pair_i_[p], smooth_pair_j_[p]) / h;
        if (free_time())
          for (int i = 0; i < npi; ++i) {
            double Mv = 0.0;
            for (int j = 0; j < npi; ++j) Mv += Msmooth_(i, j) * w(ctrl_[ctrl_of(k, j)].offset + act);
            values(uT_slots_[ctrl_of(k, i)][act]) -= ws * 2.0 * Mv / (h * T);
          }
      }
      if (free_time()) values(TT_slot_) += ws * 2.0 * smooth_quadratic(w, k) / (h * T * T);
    }
  }
  return values;
}

}  // namespace freeflex

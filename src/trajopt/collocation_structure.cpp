// The structure of the collocation NLP, fixed at construction: the layout of the
// decision vector, the defect and rate rows, and the sparsity of the Jacobian and of the
// Hessian of the Lagrangian with the slot of every term (trajopt/collocation.hpp).
#include "freeflex/trajopt/collocation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "trajopt/slot_table.hpp"

namespace freeflex {

void CollocationNlp::build() {
  build_layout();
  build_defect_rows();
  build_rate_rows();
  build_linear_rows();
  build_jacobian_structure();
  build_hessian_structure();
}

/// Sizes, point and midpoint times, control points with their quadrature weights, the
/// energy weights and the smoothness form.
void CollocationNlp::build_layout() {
  const bool trap = tr_ == Transcription::Trapezoidal;
  const int N = intervals();
  nx_ = dyn_.nx();
  nu_ = dyn_.nu();
  nz_ = nx_ + nu_;
  const int nx = nx_;
  P_ = tr_ == Transcription::HermiteSimpson ? 2 * N + 1 : N + 1;
  n_ = P_ * nz_ + num_mid_controls() * nu_ + (free_time() ? 1 : 0);
  const int npi = points_per_interval();

  // Point times, control points and their quadrature weights.
  tau_.assign(P_, 0.0);
  tau_mid_.assign(trap ? 0 : N, 0.0);
  ctrl_.clear();
  for (int j = 0; j < P_; ++j) ctrl_.push_back({point_offset(j) + nx, 0.0});
  for (int k = 0; k < num_mid_controls(); ++k) ctrl_.push_back({mid_control_offset(k), 0.0});
  double t = 0.0;
  for (int k = 0; k < N; ++k) {
    tau_[first_point(k)] = t;
    if (!trap) tau_mid_[k] = t + 0.5 * sigma_[k];
    if (tr_ == Transcription::HermiteSimpson) tau_[first_point(k) + 1] = tau_mid_[k];
    const double q2[2] = {0.5, 0.5}, q3[3] = {1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0};
    for (int i = 0; i < npi; ++i) ctrl_[ctrl_of(k, i)].qbar += sigma_[k] * (trap ? q2[i] : q3[i]);
    t += sigma_[k];
  }
  tau_[P_ - 1] = 1.0;
  W_ = problem_.energy_weights.size() ? problem_.energy_weights : Eigen::VectorXd::Ones(nu_);
  if (trap) {
    Msmooth_.resize(2, 2);
    Msmooth_ << 1, -1, -1, 1;  // (u_b − u_a)² / h = ∫ u'² of the linear piece
  } else {
    Msmooth_.resize(3, 3);  // ∫ u'² = h (d0² + d0 d1 + d1²)/3 of the quadratic piece
    Msmooth_ << 7, -8, 1, -8, 16, -8, 1, -8, 7;
    Msmooth_ /= 3.0;
  }

}

/// Defect blocks (the compressed form has one Simpson block per interval, handled apart).
void CollocationNlp::build_defect_rows() {
  const bool trap = tr_ == Transcription::Trapezoidal;
  const bool compressed = tr_ == Transcription::HermiteSimpsonCompressed;
  const int N = intervals();
  const int nx = nx_;
  int row = 0;
  blocks_.clear();
  if (compressed) {
    row = nx * N;
  } else {
    for (int k = 0; k < N; ++k) {
      const int a = first_point(k);
      if (trap) {
        blocks_.push_back({k, row, {{a, -1.0, 0.5}, {a + 1, 1.0, 0.5}}});
        row += nx;
      } else {
        blocks_.push_back({k, row, {{a, -0.5, 1.0 / 8.0}, {a + 1, 1.0, 0.0}, {a + 2, -0.5, -1.0 / 8.0}}});
        row += nx;
        blocks_.push_back({k, row, {{a, -1.0, 1.0 / 6.0}, {a + 1, 0.0, 4.0 / 6.0}, {a + 2, 1.0, 1.0 / 6.0}}});
        row += nx;
      }
    }
  }
  m_defect_ = row;

}

/// Rate rows: per interval and actuator with a finite bound, after the defects.
void CollocationNlp::build_rate_rows() {
  const bool trap = tr_ == Transcription::Trapezoidal;
  const int N = intervals();
  const int npi = points_per_interval();
  int row = m_defect_;
  rates_.clear();
  if (problem_.du_max) {
    const double inf = std::numeric_limits<double>::infinity();
    for (int k = 0; k < N; ++k) {
      std::vector<std::vector<double>> combos =
          trap ? std::vector<std::vector<double>>{{-1.0, 1.0}}
               : std::vector<std::vector<double>>{{-3.0, 4.0, -1.0}, {1.0, -4.0, 3.0}};
      for (int act = 0; act < nu_; ++act) {
        const double du = (*problem_.du_max)(act);
        if (!std::isfinite(du)) continue;
        for (const auto& combo : combos) {
          std::vector<std::pair<int, double>> coef;
          for (int i = 0; i < npi; ++i) coef.emplace_back(ctrl_[ctrl_of(k, i)].offset + act, combo[i]);
          if (free_time()) {
            rates_.push_back({row++, coef, true, -du * sigma_[k], -inf, 0.0});
            rates_.push_back({row++, coef, true, du * sigma_[k], 0.0, inf});
          } else {
            const double bound = du * sigma_[k] * problem_.duration_s;
            rates_.push_back({row++, coef, false, 0.0, -bound, bound});
          }
        }
      }
    }
  }
  m_ = row;
}

/// The other linear rows, after the rate rows: Bernstein bounds of the quadratic
/// controls (HS forms), tip deflections and the terminal modal conditions (elastic).
void CollocationNlp::build_linear_rows() {
  const int N = intervals();
  int row = m_;
  if (has_midpoints(tr_))
    for (int k = 0; k < N; ++k)
      for (int act = 0; act < nu_; ++act) {
        const double lo = problem_.u_min(act), hi = problem_.u_max(act);
        if (!std::isfinite(lo) && !std::isfinite(hi)) continue;
        // middle Bernstein coefficient of the quadratic through u_a, u_c, u_b
        std::vector<std::pair<int, double>> coef{{ctrl_[ctrl_of(k, 0)].offset + act, -0.5},
                                                 {ctrl_[ctrl_of(k, 1)].offset + act, 2.0},
                                                 {ctrl_[ctrl_of(k, 2)].offset + act, -0.5}};
        rates_.push_back({row++, coef, false, 0.0, lo, hi});
      }
  rest_modes_.clear();
  if (const ElasticDynamics* el = dyn_.elastic()) {
    constexpr int n0 = RigidDynamics::nx;
    const int n = el->n();
    const double lim = problem_.tip_deflection_limit_m;
    if (std::isfinite(lim))
      for (int j = 1; j < P_; ++j)
        for (const Eigen::RowVectorXd* phi : {&el->phi_left(), &el->phi_right()}) {
          std::vector<std::pair<int, double>> coef;
          for (int i = 0; i < n; ++i) coef.emplace_back(point_offset(j) + n0 + el->q_index() + i, (*phi)(i));
          rates_.push_back({row++, coef, false, 0.0, -lim, lim});
        }
    if (problem_.modes_at_rest == ManeuverProblem::all_modes) {
      for (int i = 0; i < n; ++i) rest_modes_.push_back(i);
    } else if (problem_.modes_at_rest > 0) {
      const std::vector<int> ex = el->excited_modes(problem_.x_initial(2));
      if (static_cast<int>(ex.size()) < problem_.modes_at_rest)
        throw std::invalid_argument("maneuver problem: modes_at_rest = " + std::to_string(problem_.modes_at_rest) +
                                    ", but the actuators excite only " + std::to_string(ex.size()) +
                                    " elastic modes of this body");
      rest_modes_.assign(ex.begin(), ex.begin() + problem_.modes_at_rest);
    }
    const int last = point_offset(P_ - 1) + n0;
    for (int j : rest_modes_) {
      const Eigen::RowVectorXd r = el->modal_rows().row(j);
      for (int side = 0; side < 2; ++side) {  // ω_j η_j(T) = 0, η_j'(T) = 0
        const int base = last + (side == 0 ? el->q_index() : el->q_rate_index());
        const double scale = side == 0 ? el->mode_frequencies()(j) : 1.0;
        std::vector<std::pair<int, double>> coef;
        for (int i = 0; i < n; ++i) coef.emplace_back(base + i, scale * r(i));
        rates_.push_back({row++, coef, false, 0.0, 0.0, 0.0});
      }
    }
  }
  m_ = row;
}

/// Triplets of the constraint Jacobian and where each block's values start.
void CollocationNlp::build_jacobian_structure() {
  const bool compressed = tr_ == Transcription::HermiteSimpsonCompressed;
  const int N = intervals();
  const int nx = nx_;
  const int Tidx = time_index();
  const auto& fpat = dyn_.jacobian_pattern();
  pat_[0].clear();
  for (int i = 0; i < nx; ++i) pat_[0].emplace_back(i, i);
  pat_[1] = fpat;
  pat_[2] = fpat;
  for (int i = 0; i < nx; ++i)
    if (std::find(fpat.begin(), fpat.end(), std::make_pair(i, i)) == fpat.end()) pat_[2].emplace_back(i, i);
  std::sort(pat_[2].begin(), pat_[2].end());
  jac_rows_.clear();
  jac_cols_.clear();
  term_start_.assign(blocks_.size(), {});
  block_time_start_.assign(blocks_.size(), -1);
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    const Block& bl = blocks_[b];
    for (const Term& tm : bl.terms) {
      term_start_[b].push_back(static_cast<int>(jac_rows_.size()));
      const int kind = (tm.beta != 0.0 ? 1 : 0) + (tm.alpha != 0.0 ? 2 : 0) - 1;
      for (const auto& rc : pat_[kind]) {
        jac_rows_.push_back(bl.row + rc.first);
        jac_cols_.push_back(point_offset(tm.point) + rc.second);
      }
    }
    if (free_time()) {
      block_time_start_[b] = static_cast<int>(jac_rows_.size());
      for (int r = 0; r < nx; ++r) {
        jac_rows_.push_back(bl.row + r);
        jac_cols_.push_back(Tidx);
      }
    }
  }
  dense_vars_.assign(compressed ? N : 0, {});
  dense_jac_start_.assign(compressed ? N : 0, 0);
  for (int k = 0; k < static_cast<int>(dense_vars_.size()); ++k) {
    std::vector<int>& v = dense_vars_[k];  // ascending: z_a, z_b, u_c, T
    for (int c = 0; c < nz_; ++c) v.push_back(point_offset(k) + c);
    for (int c = 0; c < nz_; ++c) v.push_back(point_offset(k + 1) + c);
    for (int c = 0; c < nu_; ++c) v.push_back(mid_control_offset(k) + c);
    if (free_time()) v.push_back(Tidx);
    dense_jac_start_[k] = static_cast<int>(jac_rows_.size());
    for (int r = 0; r < nx; ++r)
      for (int c : v) {
        jac_rows_.push_back(nx * k + r);
        jac_cols_.push_back(c);
      }
  }
  rate_start_.assign(rates_.size(), 0);
  for (std::size_t i = 0; i < rates_.size(); ++i) {
    rate_start_[i] = static_cast<int>(jac_rows_.size());
    for (const auto& pc : rates_[i].coef) {
      jac_rows_.push_back(rates_[i].row);
      jac_cols_.push_back(pc.first);
    }
    if (free_time() && rates_[i].timed) {
      jac_rows_.push_back(rates_[i].row);
      jac_cols_.push_back(Tidx);
    }
  }

}

/// Triplets of the Hessian's lower triangle: one slot per distinct entry, in first-use order.
void CollocationNlp::build_hessian_structure() {
  const bool compressed = tr_ == Transcription::HermiteSimpsonCompressed;
  const int N = intervals();
  const int Tidx = time_index();
  const int npi = points_per_interval();
  const auto& fpat = dyn_.jacobian_pattern();
  detail::SlotTable slots(static_cast<std::size_t>(P_) * dyn_.hessian_pattern().size() + 1024);  // an elastic NLP: ~1e5
  hess_rows_.clear();
  hess_cols_.clear();
  auto slot = [&](int r, int c) {
    if (r < c) std::swap(r, c);
    const long long key = static_cast<long long>(r) * n_ + c;
    const int known = slots.find(key);
    if (known >= 0) return known;
    const int idx = static_cast<int>(hess_rows_.size());
    slots.insert(key, idx);
    hess_rows_.push_back(r);
    hess_cols_.push_back(c);
    return idx;
  };
  fcols_.clear();
  for (const auto& rc : fpat)
    if (std::find(fcols_.begin(), fcols_.end(), rc.second) == fcols_.end()) fcols_.push_back(rc.second);
  std::sort(fcols_.begin(), fcols_.end());
  f_slots_.assign(P_, {});
  fT_slots_.assign(P_, std::vector<int>(nz_, -1));
  for (int j = 0; j < P_; ++j) {
    const int off = point_offset(j);
    for (const auto& rc : dyn_.hessian_pattern()) f_slots_[j].push_back(slot(off + rc.first, off + rc.second));
    if (free_time() && !compressed)
      for (int c : fcols_) fT_slots_[j][c] = slot(Tidx, off + c);
  }
  const int ncp = static_cast<int>(ctrl_.size());
  energy_slots_.assign(ncp, std::vector<int>(nu_, -1));
  uT_slots_.assign(ncp, std::vector<int>(nu_, -1));
  for (int cp = 0; cp < ncp; ++cp)
    for (int a = 0; a < nu_; ++a) {
      const int iu = ctrl_[cp].offset + a;
      if (problem_.w_energy > 0.0) energy_slots_[cp][a] = slot(iu, iu);
      if (free_time() && (problem_.w_energy > 0.0 || problem_.w_smooth > 0.0)) uT_slots_[cp][a] = slot(Tidx, iu);
    }
  smooth_slots_.clear();
  smooth_pair_i_.clear();
  smooth_pair_j_.clear();
  for (int i = 0; i < npi; ++i)
    for (int j = 0; j <= i; ++j) {
      smooth_pair_i_.push_back(i);
      smooth_pair_j_.push_back(j);
    }
  TT_slot_ = -1;
  if (problem_.w_smooth > 0.0) {
    smooth_slots_.assign(static_cast<std::size_t>(N) * nu_, {});
    for (int k = 0; k < N; ++k)
      for (int a = 0; a < nu_; ++a)
        for (std::size_t p = 0; p < smooth_pair_i_.size(); ++p)
          smooth_slots_[k * nu_ + a].push_back(slot(ctrl_[ctrl_of(k, smooth_pair_i_[p])].offset + a,
                                                    ctrl_[ctrl_of(k, smooth_pair_j_[p])].offset + a));
    if (free_time()) TT_slot_ = slot(Tidx, Tidx);
  }
  vib_slots_.clear();
  vib_ij_.clear();
  if (problem_.w_vibration > 0.0) {
    const int n = dyn_.elastic()->n();
    for (int side = 0; side < 2; ++side)
      for (int i = 0; i < n; ++i)
        for (int j = 0; j <= i; ++j) {
          const int base = side == 0 ? vib_q_index() : vib_qd_index();
          vib_slots_.push_back(slot(base + i, base + j));
          vib_ij_.emplace_back(i + side * n, j);
        }
  }
  build_compressed_hessian_structure(slot);
}

/// HS compressed: which entries of the q x q block Yᵀ H_c Y (+ the T row) can be nonzero,
/// and their slots per interval.
void CollocationNlp::build_compressed_hessian_structure(const std::function<int(int, int)>& slot) {
  const bool compressed = tr_ == Transcription::HermiteSimpsonCompressed;
  const int nx = nx_;
  const int Tidx = time_index();
  const auto& fpat = dyn_.jacobian_pattern();
  // H_c lives on the z-indices of dyn_.hessian_pattern(); row i < 6 of Y is
  // ½ e_i ± h/8 J(i, ·) on each knot, the u rows pick u_c, the T column is ∝ f_a − f_b.
  dense_act_.clear();
  dense_trow_.clear();
  if (compressed) {
    const int q = 2 * nz_ + nu_;  // without T
    std::vector<bool> hrow(nz_, false), act(q, false), trow(q, false);
    for (const auto& rc : dyn_.hessian_pattern()) hrow[rc.first] = hrow[rc.second] = true;
    h_rows_.clear();
    for (int i = 0; i < nz_; ++i)
      if (hrow[i]) h_rows_.push_back(i);
    // A vertex cover of H_c's pattern, greedy by degree: every entry has its row or its
    // column in h_cover_, so the block on h_rest_ x h_rest_ vanishes (for the flexible model
    // the cover is θ, ω and the commands, the rest the elastic state).
    std::vector<std::vector<int>> nbr(nz_);
    for (const auto& rc : dyn_.hessian_pattern()) {
      nbr[rc.first].push_back(rc.second);
      nbr[rc.second].push_back(rc.first);
    }
    std::vector<int> degree(nz_, 0);
    for (int i = 0; i < nz_; ++i) {
      std::sort(nbr[i].begin(), nbr[i].end());
      nbr[i].erase(std::unique(nbr[i].begin(), nbr[i].end()), nbr[i].end());
      degree[i] = static_cast<int>(nbr[i].size());
    }
    std::vector<bool> cover(nz_, false);
    for (const auto& rc : dyn_.hessian_pattern()) {
      const int i = rc.first, j = rc.second;
      if (cover[i] || cover[j]) continue;
      cover[degree[j] > degree[i] || (degree[j] == degree[i] && j < i) ? j : i] = true;
    }
    h_cover_.clear();
    h_rest_.clear();
    for (int i : h_rows_) (cover[i] ? h_cover_ : h_rest_).push_back(i);
    auto ynz = [&](int i, int c) {
      return i == c || std::find(fpat.begin(), fpat.end(), std::make_pair(i, c)) != fpat.end();
    };
    for (int side = 0; side < 2; ++side)
      for (int c = 0; c < nz_; ++c)
        for (int i = 0; i < nx; ++i) {
          if (hrow[i] && ynz(i, c)) act[side * nz_ + c] = true;
          // T row: λᵀ J_a (columns fcols_) and λᵀ J_c Y (rows of Y in fcols_)
          const bool fcol = std::find(fcols_.begin(), fcols_.end(), c) != fcols_.end();
          const bool fi = std::find(fcols_.begin(), fcols_.end(), i) != fcols_.end();
          if (fcol || (fi && ynz(i, c))) trow[side * nz_ + c] = true;
        }
    for (int a = 0; a < nu_; ++a) {
      act[2 * nz_ + a] = hrow[nx + a];
      trow[2 * nz_ + a] = true;
    }
    for (int i = 0; i < q; ++i) {
      if (act[i]) dense_act_.push_back(i);
      if (act[i] || trow[i]) dense_trow_.push_back(i);
    }
  }
  dense_slots_.assign(dense_vars_.size(), {});
  denseT_slots_.assign(dense_vars_.size(), {});
  for (std::size_t k = 0; k < dense_vars_.size(); ++k) {
    const std::vector<int>& v = dense_vars_[k];
    for (std::size_t i = 0; i < dense_act_.size(); ++i)
      for (std::size_t j = 0; j <= i; ++j) dense_slots_[k].push_back(slot(v[dense_act_[i]], v[dense_act_[j]]));
    if (free_time()) {
      for (int c : dense_trow_) denseT_slots_[k].push_back(slot(Tidx, v[c]));
      denseT_slots_[k].push_back(slot(Tidx, Tidx));
    }
  }

}

}  // namespace freeflex

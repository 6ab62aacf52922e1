#include "freeflex/trajopt/collocation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

namespace freeflex {

namespace {

constexpr int nx = RigidDynamics::nx;

std::vector<double> uniform_mesh(int intervals) {
  if (intervals < 1)
    throw std::invalid_argument("collocation: intervals = " + std::to_string(intervals) + ", expected >= 1");
  return std::vector<double>(static_cast<std::size_t>(intervals), 1.0 / intervals);
}

RigidDynamics checked_dynamics(const FlexibleBody& body, const ManeuverProblem& problem) {
  validate(body, problem);
  return RigidDynamics(body, problem.actuators);
}

}  // namespace

CollocationNlp::CollocationNlp(const FlexibleBody& body, const ManeuverProblem& problem, Transcription transcription,
                               int intervals)
    : CollocationNlp(body, problem, transcription, uniform_mesh(intervals)) {}

CollocationNlp::CollocationNlp(const FlexibleBody& body, const ManeuverProblem& problem, Transcription transcription,
                               std::vector<double> mesh_fractions)
    : dyn_(checked_dynamics(body, problem)), problem_(problem), tr_(transcription), sigma_(std::move(mesh_fractions)) {
  if (sigma_.empty()) throw std::invalid_argument("collocation: mesh_fractions is empty, expected >= 1 interval");
  double total = 0.0;
  for (std::size_t k = 0; k < sigma_.size(); ++k) {
    if (!(sigma_[k] > 0.0) || !std::isfinite(sigma_[k]))
      throw std::invalid_argument("collocation: mesh_fractions[" + std::to_string(k) + "] = " +
                                  std::to_string(sigma_[k]) + ", expected a finite value > 0");
    total += sigma_[k];
  }
  for (double& s : sigma_) s /= total;
  build();
}

int CollocationNlp::ctrl_of(int k, int i) const {
  switch (tr_) {
    case Transcription::Trapezoidal: return k + i;
    case Transcription::HermiteSimpson: return 2 * k + i;
    default: return i == 1 ? P_ + k : k + i / 2;
  }
}

void CollocationNlp::build() {
  const bool trap = tr_ == Transcription::Trapezoidal;
  const bool compressed = tr_ == Transcription::HermiteSimpsonCompressed;
  const int N = intervals();
  nu_ = dyn_.nu();
  nz_ = nx + nu_;
  P_ = tr_ == Transcription::HermiteSimpson ? 2 * N + 1 : N + 1;
  n_ = P_ * nz_ + num_mid_controls() * nu_ + (free_time() ? 1 : 0);
  const int Tidx = time_index();
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

  // Defect blocks (the compressed form has one Simpson block per interval, handled apart).
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

  // Rate rows.
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
          for (int i = 0; i < npi; ++i) coef.emplace_back(ctrl_[ctrl_of(k, i)].offset, combo[i]);
          if (free_time()) {
            rates_.push_back({row++, act, coef, -du * sigma_[k], -inf, 0.0});
            rates_.push_back({row++, act, coef, du * sigma_[k], 0.0, inf});
          } else {
            const double bound = du * sigma_[k] * problem_.duration_s;
            rates_.push_back({row++, act, coef, 0.0, -bound, bound});
          }
        }
      }
    }
  }
  m_ = row;

  // Jacobian structure.
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
      jac_cols_.push_back(pc.first + rates_[i].actuator);
    }
    if (free_time()) {
      jac_rows_.push_back(rates_[i].row);
      jac_cols_.push_back(Tidx);
    }
  }

  // Hessian structure: one slot per distinct lower-triangle entry, in first-use order.
  std::map<long long, int> slots;
  hess_rows_.clear();
  hess_cols_.clear();
  auto slot = [&](int r, int c) {
    if (r < c) std::swap(r, c);
    const long long key = static_cast<long long>(r) * n_ + c;
    auto it = slots.find(key);
    if (it != slots.end()) return it->second;
    const int idx = static_cast<int>(hess_rows_.size());
    slots.emplace(key, idx);
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
  // HS compressed: which entries of the q x q block Yᵀ H_c Y (+ the T row) can be nonzero.
  // H_c lives on the z-indices of dyn_.hessian_pattern(); row i < 6 of Y is
  // ½ e_i ± h/8 J(i, ·) on each knot, the u rows pick u_c, the T column is ∝ f_a − f_b.
  dense_act_.clear();
  dense_trow_.clear();
  if (compressed) {
    const int q = 2 * nz_ + nu_;  // without T
    std::vector<bool> hrow(nz_, false), act(q, false), trow(q, false);
    for (const auto& rc : dyn_.hessian_pattern()) hrow[rc.first] = hrow[rc.second] = true;
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

  f_.resize(nx, P_);
  J_.resize(nx, static_cast<Eigen::Index>(nz_) * P_);
  const int Nmid = compressed ? N : 0;
  xc_.resize(nx, Nmid);
  fc_.resize(nx, Nmid);
  Jc_.resize(nx, static_cast<Eigen::Index>(nz_) * Nmid);
  const int q = 2 * nz_ + nu_ + (free_time() ? 1 : 0);
  D_.resize(nx, q);
  Y_.resize(nz_, q);
  B_.resize(q, q);
  Hbuf_.resize(nz_, nz_);
  lam_eff_.resize(nx, P_);
  nu_eff_.resize(nx, P_);
  w_f_.resize(n_);
  f_valid_ = jac_valid_ = false;
}

double CollocationNlp::T_of(const Eigen::Ref<const Eigen::VectorXd>& w) const {
  return free_time() ? w(n_ - 1) : problem_.duration_s;
}

double CollocationNlp::duration(const Eigen::Ref<const Eigen::VectorXd>& w) const { return T_of(w); }

void CollocationNlp::check_size(const Eigen::Ref<const Eigen::VectorXd>& w) const {
  if (w.size() != n_)
    throw std::invalid_argument("collocation: w has " + std::to_string(w.size()) + " entries, expected " +
                                std::to_string(n_));
}

void CollocationNlp::compressed_midpoints(const Eigen::Ref<const Eigen::VectorXd>& w, bool with_jacobian) const {
  const double T = T_of(w);
  for (int k = 0; k < intervals(); ++k) {
    const double h = sigma_[k] * T;
    xc_.col(k) = 0.5 * (w.segment<nx>(point_offset(k)) + w.segment<nx>(point_offset(k + 1))) +
                 (h / 8.0) * (f_.col(k) - f_.col(k + 1));
    const auto uc = w.segment(mid_control_offset(k), nu_);
    if (with_jacobian)
      dyn_.jacobian(xc_.col(k), uc, fc_.col(k), Jc_.middleCols(static_cast<Eigen::Index>(k) * nz_, nz_));
    else
      dyn_.eval(xc_.col(k), uc, fc_.col(k));
  }
}

void CollocationNlp::ensure_f(const Eigen::Ref<const Eigen::VectorXd>& w) const {
  check_size(w);
  if (f_valid_ && w == w_f_) return;
  for (int j = 0; j < P_; ++j) {
    const int off = point_offset(j);
    dyn_.eval(w.segment(off, nx), w.segment(off + nx, nu_), f_.col(j));
  }
  if (num_mid_controls()) compressed_midpoints(w, false);
  w_f_ = w;
  f_valid_ = true;
  jac_valid_ = false;  // f_ and J_ always describe the same w
}

void CollocationNlp::ensure_jac(const Eigen::Ref<const Eigen::VectorXd>& w) const {
  check_size(w);
  if (jac_valid_ && f_valid_ && w == w_f_) return;
  for (int j = 0; j < P_; ++j) {
    const int off = point_offset(j);
    dyn_.jacobian(w.segment(off, nx), w.segment(off + nx, nu_), f_.col(j), J_.middleCols(off, nz_));
  }
  if (num_mid_controls()) compressed_midpoints(w, true);
  w_f_ = w;
  jac_valid_ = f_valid_ = true;
}

void CollocationNlp::bounds(Eigen::Ref<Eigen::VectorXd> wl, Eigen::Ref<Eigen::VectorXd> wu,
                            Eigen::Ref<Eigen::VectorXd> gl, Eigen::Ref<Eigen::VectorXd> gu) const {
  for (int j = 0; j < P_; ++j) {
    const int off = point_offset(j);
    if (j == 0) {
      wl.segment<nx>(off) = problem_.x_initial;
      wu.segment<nx>(off) = problem_.x_initial;
    } else if (j == P_ - 1) {
      wl.segment<nx>(off) = problem_.x_final;
      wu.segment<nx>(off) = problem_.x_final;
    } else {
      wl.segment<nx>(off) = problem_.x_min;
      wu.segment<nx>(off) = problem_.x_max;
    }
  }
  for (const CtrlPoint& cp : ctrl_) {
    wl.segment(cp.offset, nu_) = problem_.u_min;
    wu.segment(cp.offset, nu_) = problem_.u_max;
  }
  if (free_time()) {
    wl(n_ - 1) = problem_.t_min_s;
    wu(n_ - 1) = problem_.t_max_s;
  }
  gl.head(m_defect_).setZero();
  gu.head(m_defect_).setZero();
  for (const RateRow& r : rates_) {
    gl(r.row) = r.lower;
    gu(r.row) = r.upper;
  }
}

double CollocationNlp::smooth_quadratic(const Eigen::Ref<const Eigen::VectorXd>& w, int k) const {
  const int npi = points_per_interval();
  double q = 0.0;
  for (int act = 0; act < nu_; ++act)
    for (int i = 0; i < npi; ++i)
      for (int j = 0; j < npi; ++j)
        q += w(ctrl_[ctrl_of(k, i)].offset + act) * Msmooth_(i, j) * w(ctrl_[ctrl_of(k, j)].offset + act);
  return q;
}

double CollocationNlp::objective(const Eigen::Ref<const Eigen::VectorXd>& w) const {
  check_size(w);
  const double T = T_of(w);
  double J = problem_.w_time * T;
  if (problem_.w_energy > 0.0) {
    double E = 0.0;
    for (const CtrlPoint& cp : ctrl_) E += cp.qbar * (W_.array() * w.segment(cp.offset, nu_).array().square()).sum();
    J += problem_.w_energy * T * E;
  }
  if (problem_.w_smooth > 0.0)
    for (int k = 0; k < intervals(); ++k) J += problem_.w_smooth * smooth_quadratic(w, k) / (sigma_[k] * T);
  return J;
}

void CollocationNlp::objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& w,
                                        Eigen::Ref<Eigen::VectorXd> grad) const {
  check_size(w);
  const double T = T_of(w);
  grad.setZero();
  double dT = problem_.w_time;
  if (problem_.w_energy > 0.0)
    for (const CtrlPoint& cp : ctrl_) {
      const auto u = w.segment(cp.offset, nu_).array();
      grad.segment(cp.offset, nu_) += (problem_.w_energy * T * cp.qbar * 2.0) * (W_.array() * u).matrix();
      dT += problem_.w_energy * cp.qbar * (W_.array() * u.square()).sum();
    }
  if (problem_.w_smooth > 0.0) {
    const int npi = points_per_interval();
    for (int k = 0; k < intervals(); ++k) {
      const double h = sigma_[k] * T;
      for (int act = 0; act < nu_; ++act)
        for (int i = 0; i < npi; ++i) {
          double Mv = 0.0;
          for (int j = 0; j < npi; ++j) Mv += Msmooth_(i, j) * w(ctrl_[ctrl_of(k, j)].offset + act);
          grad(ctrl_[ctrl_of(k, i)].offset + act) += problem_.w_smooth * 2.0 * Mv / h;
        }
      dT -= problem_.w_smooth * smooth_quadratic(w, k) / (sigma_[k] * T * T);
    }
  }
  if (free_time()) grad(n_ - 1) = dT;
}

void CollocationNlp::constraints(const Eigen::Ref<const Eigen::VectorXd>& w, Eigen::Ref<Eigen::VectorXd> g) const {
  ensure_f(w);
  const double T = T_of(w);
  for (const Block& bl : blocks_) {
    const double h = sigma_[bl.interval] * T;
    auto d = g.segment<nx>(bl.row);
    d.setZero();
    for (const Term& tm : bl.terms) {
      if (tm.beta != 0.0) d += tm.beta * w.segment<nx>(point_offset(tm.point));
      if (tm.alpha != 0.0) d -= (h * tm.alpha) * f_.col(tm.point);
    }
  }
  for (int k = 0; k < num_mid_controls(); ++k) {
    const double h = sigma_[k] * T;
    g.segment<nx>(nx * k) = w.segment<nx>(point_offset(k + 1)) - w.segment<nx>(point_offset(k)) -
                            (h / 6.0) * (f_.col(k) + 4.0 * fc_.col(k) + f_.col(k + 1));
  }
  for (const RateRow& r : rates_) {
    double v = r.time_coef * (free_time() ? T : 0.0);
    for (const auto& pc : r.coef) v += pc.second * w(pc.first + r.actuator);
    g(r.row) = v;
  }
}

void CollocationNlp::compressed_jacobian_block(int k, double T) const {
  // d = x_b − x_a − h/6 (f_a + 4 f_c + f_b),  x_c = (x_a + x_b)/2 + h/8 (f_a − f_b)
  const double s = sigma_[k], h = s * T;
  const auto Ja = J_.middleCols(point_offset(k), nz_);
  const auto Jb = J_.middleCols(point_offset(k + 1), nz_);
  const auto Jc = Jc_.middleCols(static_cast<Eigen::Index>(k) * nz_, nz_);
  const auto Jcx = Jc.leftCols<nx>();
  // Y = ∂x_c/∂(z_a, z_b) in columns 0..2nz-1 (the u_c and T columns are set apart).
  Y_.topRows<nx>().leftCols(nz_) = (h / 8.0) * Ja;
  Y_.topRows<nx>().middleCols(nz_, nz_) = (-h / 8.0) * Jb;
  for (int i = 0; i < nx; ++i) {
    Y_(i, i) += 0.5;
    Y_(i, nz_ + i) += 0.5;
  }
  D_.leftCols(2 * nz_).noalias() = (-4.0 * h / 6.0) * Jcx * Y_.topRows<nx>().leftCols(2 * nz_);
  D_.leftCols(nz_) -= (h / 6.0) * Ja;
  D_.middleCols(nz_, nz_) -= (h / 6.0) * Jb;
  for (int i = 0; i < nx; ++i) {
    D_(i, i) -= 1.0;
    D_(i, nz_ + i) += 1.0;
  }
  D_.middleCols(2 * nz_, nu_) = (-4.0 * h / 6.0) * Jc.rightCols(nu_);
  if (free_time())
    D_.col(2 * nz_ + nu_) = -(s / 6.0) * (f_.col(k) + 4.0 * fc_.col(k) + f_.col(k + 1)) -
                           (4.0 * h / 6.0) * (s / 8.0) * (Jcx * (f_.col(k) - f_.col(k + 1)));
}

void CollocationNlp::jacobian_values(const Eigen::Ref<const Eigen::VectorXd>& w,
                                     Eigen::Ref<Eigen::VectorXd> values) const {
  ensure_jac(w);
  const double T = T_of(w);
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    const Block& bl = blocks_[b];
    const double h = sigma_[bl.interval] * T;
    for (std::size_t t = 0; t < bl.terms.size(); ++t) {
      const Term& tm = bl.terms[t];
      const int kind = (tm.beta != 0.0 ? 1 : 0) + (tm.alpha != 0.0 ? 2 : 0) - 1;
      const auto Jj = J_.middleCols(point_offset(tm.point), nz_);
      int idx = term_start_[b][t];
      for (const auto& rc : pat_[kind])
        values(idx++) = (rc.first == rc.second ? tm.beta : 0.0) - h * tm.alpha * Jj(rc.first, rc.second);
    }
    if (free_time()) {
      Eigen::Matrix<double, nx, 1> dT = Eigen::Matrix<double, nx, 1>::Zero();
      for (const Term& tm : bl.terms) dT -= (sigma_[bl.interval] * tm.alpha) * f_.col(tm.point);
      values.segment<nx>(block_time_start_[b]) = dT;
    }
  }
  for (int k = 0; k < num_mid_controls(); ++k) {
    compressed_jacobian_block(k, T);
    int idx = dense_jac_start_[k];
    for (int r = 0; r < nx; ++r)
      for (Eigen::Index c = 0; c < D_.cols(); ++c) values(idx++) = D_(r, c);
  }
  for (std::size_t i = 0; i < rates_.size(); ++i) {
    int idx = rate_start_[i];
    for (const auto& pc : rates_[i].coef) values(idx++) = pc.second;
    if (free_time()) values(idx) = rates_[i].time_coef;
  }
}

void CollocationNlp::hessian_values(const Eigen::Ref<const Eigen::VectorXd>& w, double obj_factor,
                                    const Eigen::Ref<const Eigen::VectorXd>& lambda,
                                    Eigen::Ref<Eigen::VectorXd> values) const {
  if (w.size() != n_ || lambda.size() != m_)
    throw std::invalid_argument("collocation: hessian_values needs w of size " + std::to_string(n_) +
                                " and lambda of size " + std::to_string(m_));
  const double T = T_of(w);
  values.setZero();
  // Each point's dynamics enter the defects linearly through h α f_j: collect the
  // multipliers per point, then one second-derivative contraction per point.
  lam_eff_.setZero();
  nu_eff_.setZero();
  for (const Block& bl : blocks_) {
    const double s = sigma_[bl.interval];
    const auto mu = lambda.segment<nx>(bl.row);
    for (const Term& tm : bl.terms) {
      if (tm.alpha == 0.0) continue;
      lam_eff_.col(tm.point) -= (s * T * tm.alpha) * mu;
      nu_eff_.col(tm.point) -= (s * tm.alpha) * mu;  // ∂/∂T of the same terms
    }
  }
  if (free_time() || num_mid_controls()) ensure_jac(w);
  const auto& hpat = dyn_.hessian_pattern();

  // HS compressed: λᵀd = λᵀ(x_b − x_a) − h/6 λᵀ(f_a + f_b) + s g(y),  s = −4h/6,
  // g = λᵀ f(y), y = (x_c, u_c). ∇²(s g) = s Yᵀ H_c Y + s μᵀ∇²x_c (μ = J_c,xᵀ λ), with
  // ∇²x_c = h/8 (f_a'' − f_b''), plus the terms from s and h depending on T.
  for (int k = 0; k < num_mid_controls(); ++k) {
    const double sg = sigma_[k], h = sg * T, s = -4.0 * h / 6.0, ds = -4.0 * sg / 6.0;
    const auto lam = lambda.segment<nx>(nx * k);
    const auto Ja = J_.middleCols(point_offset(k), nz_);
    const auto Jb = J_.middleCols(point_offset(k + 1), nz_);
    const auto Jc = Jc_.middleCols(static_cast<Eigen::Index>(k) * nz_, nz_);
    const Eigen::Matrix<double, nx, 1> mu = Jc.leftCols<nx>().transpose() * lam;
    lam_eff_.col(k) += -(h / 6.0) * lam + (s * h / 8.0) * mu;
    lam_eff_.col(k + 1) += -(h / 6.0) * lam - (s * h / 8.0) * mu;
    // Y = ∂y/∂(z_a, z_b, u_c, T)
    Y_.setZero();
    Y_.topRows<nx>().leftCols(nz_) = (h / 8.0) * Ja;
    Y_.topRows<nx>().middleCols(nz_, nz_) = (-h / 8.0) * Jb;
    for (int i = 0; i < nx; ++i) {
      Y_(i, i) += 0.5;
      Y_(i, nz_ + i) += 0.5;
    }
    for (int i = 0; i < nu_; ++i) Y_(nx + i, 2 * nz_ + i) = 1.0;
    const int q = static_cast<int>(Y_.cols());
    if (free_time()) Y_.col(q - 1).head<nx>() = (sg / 8.0) * (f_.col(k) - f_.col(k + 1));
    dyn_.hessian_contraction(xc_.col(k), w.segment(mid_control_offset(k), nu_), lam, Hbuf_);
    Hbuf_ *= s;
    B_.noalias() = Y_.transpose() * Hbuf_ * Y_;
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
    dyn_.hessian_contraction(w.segment(off, nx), w.segment(off + nx, nu_), lam_eff_.col(j), Hbuf_);
    for (std::size_t e = 0; e < hpat.size(); ++e) values(f_slots_[j][e]) += Hbuf_(hpat[e].first, hpat[e].second);
    if (free_time() && !num_mid_controls()) {
      const auto Jj = J_.middleCols(off, nz_);
      for (int c : fcols_) values(fT_slots_[j][c]) += nu_eff_.col(j).dot(Jj.col(c));
    }
  }
  if (obj_factor == 0.0) return;
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
}

double CollocationNlp::max_defect(const Eigen::Ref<const Eigen::VectorXd>& w) const {
  Eigen::VectorXd g(m_);
  constraints(w, g);
  return m_defect_ ? g.head(m_defect_).cwiseAbs().maxCoeff() : 0.0;
}

void CollocationNlp::midpoints(const Eigen::Ref<const Eigen::VectorXd>& w, Eigen::MatrixXd& x_mid,
                               Eigen::MatrixXd& u_mid) const {
  if (!has_midpoints(tr_)) throw std::logic_error("collocation: the trapezoidal transcription has no midpoints");
  check_size(w);
  const int N = intervals();
  x_mid.resize(N, nx);
  u_mid.resize(N, nu_);
  if (num_mid_controls()) ensure_f(w);
  for (int k = 0; k < N; ++k) {
    if (num_mid_controls())
      x_mid.row(k) = xc_.col(k).transpose();
    else
      x_mid.row(k) = w.segment<nx>(point_offset(first_point(k) + 1)).transpose();
    u_mid.row(k) = w.segment(ctrl_[ctrl_of(k, 1)].offset, nu_).transpose();
  }
}

std::shared_ptr<const CollocationTrajectory> CollocationNlp::trajectory(const Eigen::Ref<const Eigen::VectorXd>& w) const {
  check_size(w);
  const int N = intervals();
  const double T = T_of(w);
  Eigen::VectorXd t(N + 1);
  Eigen::MatrixXd x(N + 1, nx), u(N + 1, nu_), x_mid, u_mid;
  for (int k = 0; k <= N; ++k) {
    const int j = first_point(k);
    t(k) = tau_[j] * T;
    x.row(k) = w.segment<nx>(point_offset(j)).transpose();
    u.row(k) = w.segment(point_offset(j) + nx, nu_).transpose();
  }
  if (has_midpoints(tr_)) midpoints(w, x_mid, u_mid);
  return std::make_shared<const CollocationTrajectory>(dyn_, tr_, std::move(t), std::move(x), std::move(u),
                                                       std::move(u_mid));
}

}  // namespace freeflex

// Evaluation of the collocation NLP (trajopt/collocation.hpp): bounds, objective and
// gradient, defects and their Jacobian through the workspace's cache of f and ∂f, and
// the trajectory a solution stands for.
#include "freeflex/trajopt/collocation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace freeflex {

namespace {

std::vector<double> uniform_mesh(int intervals) {
  if (intervals < 1)
    throw std::invalid_argument("collocation: intervals = " + std::to_string(intervals) + ", expected >= 1");
  return std::vector<double>(static_cast<std::size_t>(intervals), 1.0 / intervals);
}

ManeuverDynamics checked_dynamics(const FlexibleBody& body, const ManeuverProblem& problem) {
  validate(body, problem);
  if (!problem.elastic) return ManeuverDynamics(body, problem.actuators);
  return ManeuverDynamics(body, problem.actuators, std::make_shared<const ElasticDynamics>(body, problem.actuators, problem.elastic_modes));
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

double CollocationNlp::T_of(const Eigen::Ref<const Eigen::VectorXd>& w) const {
  return free_time() ? w(n_ - 1) : problem_.duration_s;
}

double CollocationNlp::duration(const Eigen::Ref<const Eigen::VectorXd>& w) const { return T_of(w); }

int CollocationNlp::vib_q_index() const {
  return point_offset(P_ - 1) + RigidDynamics::nx + dyn_.elastic()->q_index();
}

int CollocationNlp::vib_qd_index() const {
  return point_offset(P_ - 1) + RigidDynamics::nx + dyn_.elastic()->q_rate_index();
}

double CollocationNlp::terminal_vibration_energy(const Eigen::Ref<const Eigen::VectorXd>& w) const {
  if (!dyn_.elastic()) return 0.0;
  const ElasticDynamics& el = *dyn_.elastic();
  const int n = el.n();
  const auto q = w.segment(vib_q_index(), n), qd = w.segment(vib_qd_index(), n);
  return 0.5 * qd.dot(el.condensed_mass() * qd) + 0.5 * q.dot(el.stiffness() * q);  // eq. 6.8
}

void CollocationNlp::check_size(const Eigen::Ref<const Eigen::VectorXd>& w) const {
  if (w.size() != n_)
    throw std::invalid_argument("collocation: w has " + std::to_string(w.size()) + " entries, expected " +
                                std::to_string(n_));
}

CollocationNlp::Data CollocationNlp::create_data() const {
  const bool compressed = tr_ == Transcription::HermiteSimpsonCompressed;
  const int nx = nx_;
  Data data;
  Data::Cache& c = data.cache;
  c.f.resize(nx, P_);
  c.J.resize(nx, static_cast<Eigen::Index>(nz_) * P_);
  const int Nmid = compressed ? intervals() : 0;
  c.xc.resize(nx, Nmid);
  c.fc.resize(nx, Nmid);
  c.Jc.resize(nx, static_cast<Eigen::Index>(nz_) * Nmid);
  const int q = 2 * nz_ + nu_ + (free_time() ? 1 : 0);
  c.D.resize(nx, q);
  c.Y.resize(nz_, q);
  c.B.resize(q, q);
  c.lam_eff.resize(nx, P_);
  c.nu_eff.resize(nx, P_);
  c.w.resize(n_);
  c.dyn = dyn_.create_data();
  data.constraints.resize(m_);
  data.jacobian.resize(jacobian_nonzeros());
  data.hessian.resize(hessian_nonzeros());
  return data;
}

void CollocationNlp::compressed_midpoints(Data::Cache& c, const Eigen::Ref<const Eigen::VectorXd>& w,
                                          bool with_jacobian) const {
  const int nx = nx_;
  const double T = T_of(w);
  for (int k = 0; k < intervals(); ++k) {
    const double h = sigma_[k] * T;
    c.xc.col(k) = 0.5 * (w.segment(point_offset(k), nx) + w.segment(point_offset(k + 1), nx)) +
                  (h / 8.0) * (c.f.col(k) - c.f.col(k + 1));
    const auto uc = w.segment(mid_control_offset(k), nu_);
    if (with_jacobian) {
      dyn_.calc_diff(c.dyn, c.xc.col(k), uc);
      c.fc.col(k) = c.dyn.f;
      c.Jc.middleCols(static_cast<Eigen::Index>(k) * nz_, nz_) = c.dyn.J;
    } else {
      c.fc.col(k) = dyn_.calc(c.dyn, c.xc.col(k), uc);
    }
  }
}

void CollocationNlp::ensure_f(Data::Cache& c, const Eigen::Ref<const Eigen::VectorXd>& w) const {
  check_size(w);
  if (c.f_valid && w == c.w) return;
  for (int j = 0; j < P_; ++j) {
    const int off = point_offset(j);
    c.f.col(j) = dyn_.calc(c.dyn, w.segment(off, nx_), w.segment(off + nx_, nu_));
  }
  if (num_mid_controls()) compressed_midpoints(c, w, false);
  c.w = w;
  c.f_valid = true;
  c.jac_valid = false;  // f and J always describe the same w
}

void CollocationNlp::ensure_jac(Data::Cache& c, const Eigen::Ref<const Eigen::VectorXd>& w) const {
  check_size(w);
  if (c.jac_valid && c.f_valid && w == c.w) return;
  for (int j = 0; j < P_; ++j) {
    const int off = point_offset(j);
    dyn_.calc_diff(c.dyn, w.segment(off, nx_), w.segment(off + nx_, nu_));
    c.f.col(j) = c.dyn.f;
    c.J.middleCols(off, nz_) = c.dyn.J;
  }
  if (num_mid_controls()) compressed_midpoints(c, w, true);
  c.w = w;
  c.jac_valid = c.f_valid = true;
}

CollocationNlp::Bounds CollocationNlp::bounds() const {
  Bounds b;
  b.w_lower.resize(n_);
  b.w_upper.resize(n_);
  b.g_lower.resize(m_);
  b.g_upper.resize(m_);
  Eigen::VectorXd &wl = b.w_lower, &wu = b.w_upper, &gl = b.g_lower, &gu = b.g_upper;
  constexpr int n0 = RigidDynamics::nx;
  const int n1 = nx_ - n0;
  const double inf = std::numeric_limits<double>::infinity();
  for (int j = 0; j < P_; ++j) {
    const int off = point_offset(j);
    if (j == 0) {
      wl.segment<n0>(off) = problem_.x_initial;
      wu.segment<n0>(off) = problem_.x_initial;
      wl.segment(off + n0, n1).setZero();  // the elastic motion starts at rest
      wu.segment(off + n0, n1).setZero();
    } else {
      if (j == P_ - 1) {
        wl.segment<n0>(off) = problem_.x_final;
        wu.segment<n0>(off) = problem_.x_final;
      } else {
        wl.segment<n0>(off) = problem_.x_min;
        wu.segment<n0>(off) = problem_.x_max;
      }
      wl.segment(off + n0, n1).setConstant(-inf);
      wu.segment(off + n0, n1).setConstant(inf);
    }
  }
  for (const CtrlPoint& cp : ctrl_) {
    wl.segment(cp.offset, nu_) = problem_.u_min;
    wu.segment(cp.offset, nu_) = problem_.u_max;
  }
  if (problem_.zero_end_commands)
    for (int j : {0, P_ - 1}) {
      wl.segment(point_offset(j) + nx_, nu_).setZero();
      wu.segment(point_offset(j) + nx_, nu_).setZero();
    }
  if (free_time()) {
    wl(n_ - 1) = problem_.t_min_s;
    wu(n_ - 1) = problem_.t_max_s;
  }
  gl.head(m_defect_).setZero();
  gu.head(m_defect_).setZero();
  for (const LinearRow& r : rates_) {
    gl(r.row) = r.lower;
    gu(r.row) = r.upper;
  }
  return b;
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
  if (problem_.w_vibration > 0.0) J += problem_.w_vibration * terminal_vibration_energy(w);
  return J;
}

Eigen::VectorXd CollocationNlp::objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& w) const {
  check_size(w);
  const double T = T_of(w);
  Eigen::VectorXd grad = Eigen::VectorXd::Zero(n_);
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
  if (problem_.w_vibration > 0.0) {
    const ElasticDynamics& el = *dyn_.elastic();
    const int n = el.n(), iq = vib_q_index(), iqd = vib_qd_index();
    grad.segment(iq, n) += problem_.w_vibration * (el.stiffness() * w.segment(iq, n));
    grad.segment(iqd, n) += problem_.w_vibration * (el.condensed_mass() * w.segment(iqd, n));
  }
  if (free_time()) grad(n_ - 1) = dT;
  return grad;
}

const Eigen::VectorXd& CollocationNlp::constraints(Data& data, const Eigen::Ref<const Eigen::VectorXd>& w) const {
  data.constraints.resize(m_);
  constraints_into(data.cache, w, data.constraints);
  return data.constraints;
}

void CollocationNlp::constraints_into(Data::Cache& c, const Eigen::Ref<const Eigen::VectorXd>& w,
                                      Eigen::Ref<Eigen::VectorXd> g) const {
  ensure_f(c, w);
  const int nx = nx_;
  const Eigen::MatrixXd& f_ = c.f;
  const Eigen::MatrixXd& fc_ = c.fc;
  const double T = T_of(w);
  for (const Block& bl : blocks_) {
    const double h = sigma_[bl.interval] * T;
    auto d = g.segment(bl.row, nx);
    d.setZero();
    for (const Term& tm : bl.terms) {
      if (tm.beta != 0.0) d += tm.beta * w.segment(point_offset(tm.point), nx);
      if (tm.alpha != 0.0) d -= (h * tm.alpha) * f_.col(tm.point);
    }
  }
  for (int k = 0; k < num_mid_controls(); ++k) {
    const double h = sigma_[k] * T;
    g.segment(nx * k, nx) = w.segment(point_offset(k + 1), nx) - w.segment(point_offset(k), nx) -
                            (h / 6.0) * (f_.col(k) + 4.0 * fc_.col(k) + f_.col(k + 1));
  }
  for (const LinearRow& r : rates_) {
    double v = r.time_coef * (free_time() ? T : 0.0);
    for (const auto& pc : r.coef) v += pc.second * w(pc.first);
    g(r.row) = v;
  }
}

void CollocationNlp::compressed_jacobian_block(Data::Cache& c, int k, double T) const {
  const int nx = nx_;
  const Eigen::MatrixXd &f_ = c.f, &fc_ = c.fc, &J_ = c.J, &Jc_ = c.Jc;
  Eigen::MatrixXd &Y_ = c.Y, &D_ = c.D;
  // d = x_b − x_a − h/6 (f_a + 4 f_c + f_b),  x_c = (x_a + x_b)/2 + h/8 (f_a − f_b)
  const double s = sigma_[k], h = s * T;
  const auto Ja = J_.middleCols(point_offset(k), nz_);
  const auto Jb = J_.middleCols(point_offset(k + 1), nz_);
  const auto Jc = Jc_.middleCols(static_cast<Eigen::Index>(k) * nz_, nz_);
  const auto Jcx = Jc.leftCols(nx);
  // Y = ∂x_c/∂(z_a, z_b) in columns 0..2nz-1 (the u_c and T columns are set apart).
  Y_.topRows(nx).leftCols(nz_) = (h / 8.0) * Ja;
  Y_.topRows(nx).middleCols(nz_, nz_) = (-h / 8.0) * Jb;
  for (int i = 0; i < nx; ++i) {
    Y_(i, i) += 0.5;
    Y_(i, nz_ + i) += 0.5;
  }
  D_.leftCols(2 * nz_).noalias() = (-4.0 * h / 6.0) * Jcx * Y_.topRows(nx).leftCols(2 * nz_);
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

const Eigen::VectorXd& CollocationNlp::jacobian_values(Data& data, const Eigen::Ref<const Eigen::VectorXd>& w) const {
  Data::Cache& c = data.cache;
  ensure_jac(c, w);
  const Eigen::MatrixXd &f_ = c.f, &J_ = c.J, &D_ = c.D;
  Eigen::VectorXd& values = data.jacobian;
  values.resize(jacobian_nonzeros());
  const int nx = nx_;
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
      auto dT = values.segment(block_time_start_[b], nx);
      dT.setZero();
      for (const Term& tm : bl.terms) dT -= (sigma_[bl.interval] * tm.alpha) * f_.col(tm.point);
    }
  }
  for (int k = 0; k < num_mid_controls(); ++k) {
    compressed_jacobian_block(c, k, T);
    int idx = dense_jac_start_[k];
    for (int r = 0; r < nx; ++r)
      for (Eigen::Index col = 0; col < D_.cols(); ++col) values(idx++) = D_(r, col);
  }
  for (std::size_t i = 0; i < rates_.size(); ++i) {
    int idx = rate_start_[i];
    for (const auto& pc : rates_[i].coef) values(idx++) = pc.second;
    if (free_time() && rates_[i].timed) values(idx) = rates_[i].time_coef;
  }
  return values;
}

double CollocationNlp::max_defect(const Eigen::Ref<const Eigen::VectorXd>& w) const {
  Data data = create_data();
  const Eigen::VectorXd& g = constraints(data, w);
  return m_defect_ ? g.head(m_defect_).cwiseAbs().maxCoeff() : 0.0;
}

CollocationNlp::Midpoints CollocationNlp::midpoints(const Eigen::Ref<const Eigen::VectorXd>& w) const {
  if (!has_midpoints(tr_)) throw std::logic_error("collocation: the trapezoidal transcription has no midpoints");
  check_size(w);
  const int N = intervals();
  const int nx = nx_;
  Midpoints mid;
  Eigen::MatrixXd &x_mid = mid.x, &u_mid = mid.u;
  x_mid.resize(N, nx);
  u_mid.resize(N, nu_);
  Data data = create_data();
  if (num_mid_controls()) ensure_f(data.cache, w);
  for (int k = 0; k < N; ++k) {
    if (num_mid_controls())
      x_mid.row(k) = data.cache.xc.col(k).transpose();
    else
      x_mid.row(k) = w.segment(point_offset(first_point(k) + 1), nx).transpose();
    u_mid.row(k) = w.segment(ctrl_[ctrl_of(k, 1)].offset, nu_).transpose();
  }
  return mid;
}

Eigen::VectorXd CollocationNlp::carried_bound_multipliers(const CollocationNlp& from,
                                                          const Eigen::Ref<const Eigen::VectorXd>& z) const {
  if (from.tr_ != tr_ || from.nz_ != nz_ || from.nx_ != nx_ || from.free_time() != free_time() ||
      z.size() != from.n_)
    return {};
  Eigen::VectorXd out = Eigen::VectorXd::Zero(n_);
  // the places of one kind, in time order: knots (every point but the separated form's
  // midpoints), the separated form's midpoints, the compressed form's midpoint controls
  struct Place {
    double tau, weight;  // time fraction; quadrature weight of its point (ctrl_'s qbar)
    int offset;          // index of its first entry in w
  };
  const auto places = [](const CollocationNlp& nlp, int kind) {
    std::vector<Place> p;
    if (kind < 2) {
      for (int j = 0; j < nlp.P_; ++j)
        if (nlp.is_knot(j) == (kind == 0)) p.push_back({nlp.tau_[j], nlp.ctrl_[j].qbar, nlp.point_offset(j)});
    } else {
      for (int k = 0; k < nlp.num_mid_controls(); ++k)
        p.push_back({nlp.tau_mid_[k], nlp.ctrl_[nlp.P_ + k].qbar, nlp.mid_control_offset(k)});
    }
    return p;
  };
  // A fixed variable of `from` (the boundary states, end commands held at zero) has no
  // multiplier of its own (Ipopt takes it out of the problem and returns 0): the entries
  // of a component come from the nearest place where `from` leaves it free.
  const Bounds fb = from.bounds();
  std::vector<const Place*> free_places;
  for (int kind = 0; kind < 3; ++kind) {
    const std::vector<Place> mine = places(*this, kind), theirs = places(from, kind);
    const int width = kind == 2 ? nu_ : nz_;
    for (int i = 0; i < width; ++i) {
      free_places.clear();
      for (const Place& q : theirs)
        if (fb.w_lower(q.offset + i) != fb.w_upper(q.offset + i)) free_places.push_back(&q);
      if (free_places.empty()) continue;
      std::size_t c = 0;
      for (const Place& p : mine) {  // both in time order: the nearest (on a tie the later) moves forward only
        while (c + 1 < free_places.size() &&
               std::abs(free_places[c + 1]->tau - p.tau) <= std::abs(free_places[c]->tau - p.tau))
          ++c;
        const Place& q = *free_places[c];
        out(p.offset + i) = (q.weight > 0.0 ? p.weight / q.weight : 1.0) * z(q.offset + i);
      }
    }
  }
  if (free_time()) out(time_index()) = z(from.time_index());
  return out;
}

std::shared_ptr<const CollocationTrajectory> CollocationNlp::trajectory(const Eigen::Ref<const Eigen::VectorXd>& w) const {
  check_size(w);
  const int N = intervals();
  const double T = T_of(w);
  const int nx = nx_;
  Eigen::VectorXd t(N + 1);
  Eigen::MatrixXd x(N + 1, nx), u(N + 1, nu_);
  Midpoints mid;
  for (int k = 0; k <= N; ++k) {
    const int j = first_point(k);
    t(k) = tau_[j] * T;
    x.row(k) = w.segment(point_offset(j), nx).transpose();
    u.row(k) = w.segment(point_offset(j) + nx, nu_).transpose();
  }
  if (has_midpoints(tr_)) mid = midpoints(w);
  return std::make_shared<const CollocationTrajectory>(dyn_, tr_, std::move(t), std::move(x), std::move(u),
                                                       std::move(mid.u));
}

}  // namespace freeflex

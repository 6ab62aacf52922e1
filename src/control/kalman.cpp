// Sensors, the exact discretization of the first-order model between samples, and the
// time-varying Kalman filter (control/lqg.hpp, docs/theory.md section 12).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "freeflex/control/lqg.hpp"
#include "freeflex/control/lqr.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

std::string num(double v) { return util::format_number(v, 10); }

}  // namespace

Eigen::MatrixXd output_matrix(const FlexibleBody& body, const std::vector<Sensor>& sensors) {
  const int N = body.dofs(), p = static_cast<int>(sensors.size());
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(p, 2 * N);
  const Beam& beam = body.beam();
  for (int i = 0; i < p; ++i) {
    const Sensor& s = sensors[i];
    const std::string who = "output_matrix: sensor " + std::to_string(i) + " ('" + s.name + "')";
    if (!(s.noise_density >= 0.0) || !std::isfinite(s.noise_density))
      throw std::invalid_argument(who + ": noise_density = " + num(s.noise_density) + ", must be finite and >= 0");
    switch (s.type) {
      case Sensor::Type::GyroAttitude: C(i, 2) = 1.0; break;
      case Sensor::Type::GyroRate: C(i, N + 2) = 1.0; break;
      case Sensor::Type::Strain:
      case Sensor::Type::TipDisplacement: {
        if (!(s.position_m >= 0.0 && s.position_m <= beam.length()))
          throw std::invalid_argument(who + ": position_m = " + num(s.position_m) + ", must be in [0, " +
                                      num(beam.length()) + "] (distance from the left end)");
        const BasisValues v = body.basis().evaluate(beam.x_of(s.position_m));
        C.row(i).segment(3, body.n()) = s.type == Sensor::Type::Strain ? v.ddphi : v.phi;
        break;
      }
    }
  }
  return C;
}

Eigen::VectorXd measurement_variance(const std::vector<Sensor>& sensors, double sample_rate_hz) {
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz))
    throw std::invalid_argument("measurement_variance: sample_rate_hz = " + num(sample_rate_hz) +
                                ", must be finite and > 0");
  Eigen::VectorXd v(static_cast<Eigen::Index>(sensors.size()));
  for (std::size_t i = 0; i < sensors.size(); ++i)
    v(static_cast<Eigen::Index>(i)) = sensors[i].noise_density * sensors[i].noise_density * sample_rate_hz;  // eq. 12.2
  return v;
}

std::vector<double> sample_times(double t0, double tf, double sample_rate_hz) {
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz))
    throw std::invalid_argument("sample_times: sample_rate_hz = " + num(sample_rate_hz) + ", must be finite and > 0");
  if (!(tf > t0) || !std::isfinite(t0) || !std::isfinite(tf))
    throw std::invalid_argument("sample_times: expected finite t0 < tf, got t0 = " + num(t0) + ", tf = " + num(tf));
  const double Ts = 1.0 / sample_rate_hz;
  const double count = (tf - t0) / Ts;
  if (count > 1e7) throw std::invalid_argument("sample_times: more than 1e7 samples (" + num(count) + ")");
  const long K = static_cast<long>(std::ceil(count - 1e-9));
  std::vector<double> t;
  t.reserve(static_cast<std::size_t>(K) + 1);
  for (long k = 0; k < K; ++k) t.push_back(t0 + static_cast<double>(k) * Ts);  // k Ts, not a running sum: no drift
  t.push_back(tf);
  return t;
}

void validate(const DiscretizeOptions& options) { validate(options.integrator); }

DiscreteLtv discretize(const LtvSystem& system, const std::vector<double>& times, const Eigen::MatrixXd& W,
                       const DiscretizeOptions& options) {
  validate(options);
  const int n = system.state_size, m = system.input_size;
  if (times.size() < 2) throw std::invalid_argument("discretize: expected at least two sample times");
  for (std::size_t k = 1; k < times.size(); ++k)
    if (!(times[k] > times[k - 1])) throw std::invalid_argument("discretize: sample times must be ascending");
  check_positive_semidefinite(W, m, "W", "discretize");
  // Q is integrated divided by σ = max|W| (1 when W = 0), so that atol means the same
  // for it as for Φ (the intensities can be ~1e-8).
  const double sigma = W.size() && W.cwiseAbs().maxCoeff() > 0.0 ? W.cwiseAbs().maxCoeff() : 1.0;
  const int nn = n * n, nm = n * m, dim = 2 * nn + nm + n;
  OdeSystem sys;
  sys.dim = dim;
  sys.rhs = [&](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> yd) {
    const StateSpace ss = system.state_space(at);
    Eigen::Map<const Eigen::MatrixXd> Phi(y.data(), n, n), Gam(y.data() + nn, n, m), Q(y.data() + nn + nm + n, n, n);
    Eigen::Map<const Eigen::VectorXd> d(y.data() + nn + nm, n);
    Eigen::Map<Eigen::MatrixXd> dPhi(yd.data(), n, n), dGam(yd.data() + nn, n, m), dQ(yd.data() + nn + nm + n, n, n);
    Eigen::Map<Eigen::VectorXd> dd(yd.data() + nn + nm, n);
    dPhi.noalias() = ss.A * Phi;  // eq. 12.3
    dGam.noalias() = ss.A * Gam;
    dGam += ss.B;
    dd.noalias() = ss.A * d;
    dd += ss.g;
    const Eigen::MatrixXd AQ = ss.A * Q;
    dQ = AQ + AQ.transpose();
    dQ.noalias() += ss.B * (W / sigma) * ss.B.transpose();
    return yd.allFinite();
  };
  sys.last_error = [] { return std::string("the discretization's right-hand side is not finite"); };
  // each evaluation is two n x n by n products (AΦ, AQ): charged like a Riccati step
  sys.step_work = riccati_step_work(n);

  DiscreteLtv r;
  r.t = times;
  Eigen::VectorXd y0 = Eigen::VectorXd::Zero(dim);
  Eigen::Map<Eigen::MatrixXd>(y0.data(), n, n).setIdentity();
  for (std::size_t k = 0; k + 1 < times.size(); ++k) {
    const IntegrationResult ir = integrate(sys, y0, {times[k], times[k + 1]}, system.breakpoints, options.integrator);
    if (!ir.ok()) {
      r.status = IntegrationStatus::Failed;
      r.message = "discretization over [" + num(times[k]) + ", " + num(times[k + 1]) + "] s failed: " + ir.message;
      return r;
    }
    const Eigen::VectorXd y = ir.x.row(ir.x.rows() - 1).transpose();
    r.Phi.push_back(Eigen::Map<const Eigen::MatrixXd>(y.data(), n, n));
    r.Gamma.push_back(Eigen::Map<const Eigen::MatrixXd>(y.data() + nn, n, m));
    r.d.push_back(Eigen::Map<const Eigen::VectorXd>(y.data() + nn + nm, n));
    Eigen::MatrixXd Q = Eigen::Map<const Eigen::MatrixXd>(y.data() + nn + nm + n, n, n) * sigma;
    r.Qd.push_back(0.5 * (Q + Q.transpose()));
  }
  r.status = IntegrationStatus::Completed;
  r.message = "completed";
  return r;
}

Eigen::VectorXd KalmanResult::update(int k, const Eigen::Ref<const Eigen::VectorXd>& x_prior,
                                     const Eigen::Ref<const Eigen::VectorXd>& y) const {
  return x_prior + L[static_cast<std::size_t>(k)] * (y - C * x_prior);
}

Eigen::VectorXd KalmanResult::predict(int k, const Eigen::Ref<const Eigen::VectorXd>& x_post,
                                      const Eigen::Ref<const Eigen::VectorXd>& u) const {
  const std::size_t i = static_cast<std::size_t>(k);
  return model.Phi[i] * x_post + model.Gamma[i] * u + model.d[i];
}

KalmanResult design_kalman(const LtvSystem& system, const Eigen::MatrixXd& C, const Eigen::MatrixXd& V,
                           const Eigen::MatrixXd& W, const Eigen::MatrixXd& P0, double t0, double tf,
                           double sample_rate_hz, const DiscretizeOptions& options) {
  const std::string where = "design_kalman";
  const int n = system.state_size, p = static_cast<int>(C.rows());
  if (C.cols() != n)
    throw std::invalid_argument(where + ": C must have " + std::to_string(n) + " columns, got " +
                                std::to_string(C.cols()));
  if (p < 1) throw std::invalid_argument(where + ": expected at least one sensor (C has no rows)");
  check_positive_definite(V, p, "V", where);
  check_positive_semidefinite(P0, n, "P0", where);
  const std::vector<double> times = sample_times(t0, tf, sample_rate_hz);
  KalmanResult r;
  r.C = C;
  r.V = V;
  r.model = discretize(system, times, W, options);
  if (!r.model.ok()) {
    r.status = KalmanResult::Status::DiscretizationFailed;
    r.message = r.model.message;
    return r;
  }
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  Eigen::MatrixXd P = P0;
  for (std::size_t k = 0; k < times.size(); ++k) {
    r.P_prior.push_back(P);
    const Eigen::MatrixXd S = C * P * C.transpose() + V;  // eq. 12.4
    const Eigen::LLT<Eigen::MatrixXd> llt(S);
    if (llt.info() != Eigen::Success || !S.allFinite()) {
      r.status = KalmanResult::Status::NotPositiveDefinite;
      r.message = "the innovation covariance is not positive definite at t = " + num(times[k]) + " s";
      return r;
    }
    const Eigen::MatrixXd L = llt.solve(C * P).transpose();
    const Eigen::MatrixXd IKC = I - L * C;
    Eigen::MatrixXd Pp = IKC * P * IKC.transpose() + L * V * L.transpose();  // Joseph form: stays PSD
    Pp = 0.5 * (Pp + Pp.transpose());
    r.L.push_back(L);
    r.P_post.push_back(Pp);
    if (k + 1 < times.size()) {
      P = r.model.Phi[k] * Pp * r.model.Phi[k].transpose() + r.model.Qd[k];
      P = 0.5 * (P + P.transpose());
    }
  }
  r.status = KalmanResult::Status::Solved;
  r.message = "solved";
  return r;
}

// splitmix64 (Steele, Lea, Flood 2014): a full-period 64-bit generator, a few lines.
std::uint64_t NormalStream::bits() {
  std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

double NormalStream::next() {
  if (have_spare_) {
    have_spare_ = false;
    return spare_;
  }
  // Box–Muller on two uniforms in (0, 1]: 53 random bits each.
  const double u1 = (static_cast<double>(bits() >> 11) + 1.0) * 0x1.0p-53;
  const double u2 = static_cast<double>(bits() >> 11) * 0x1.0p-53;
  const double r = std::sqrt(-2.0 * std::log(u1));
  const double a = 6.283185307179586476925 * u2;
  spare_ = r * std::sin(a);
  have_spare_ = true;
  return r * std::cos(a);
}

}  // namespace freeflex

namespace freeflex {

TvlqrResult solve_discrete_tvlqr(const DiscreteLtv& dm, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& R,
                                 const Eigen::MatrixXd& Qf) {
  const std::string where = "solve_discrete_tvlqr";
  if (!dm.ok() || dm.Phi.empty()) throw std::invalid_argument(where + ": the discrete model was not computed");
  const int n = static_cast<int>(dm.Phi.front().rows()), m = static_cast<int>(dm.Gamma.front().cols());
  check_positive_semidefinite(Q, n, "Q", where);
  check_positive_semidefinite(Qf, n, "Qf", where);
  check_positive_definite(R, m, "R", where);
  const auto clock0 = std::chrono::steady_clock::now();
  const std::size_t K = dm.Phi.size();
  TvlqrResult r;
  r.t = dm.t;
  r.K.assign(K + 1, Eigen::MatrixXd::Zero(m, n));
  r.feedforward = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(K + 1), m);
  r.Qf = Qf;
  Eigen::MatrixXd P = Qf;
  Eigen::VectorXd s = Eigen::VectorXd::Zero(n);
  for (std::size_t j = K; j-- > 0;) {
    const double Ts = dm.t[j + 1] - dm.t[j];
    const Eigen::MatrixXd& Phi = dm.Phi[j];
    const Eigen::MatrixXd& G = dm.Gamma[j];
    const Eigen::MatrixXd PG = P * G;
    const Eigen::MatrixXd S = R * Ts + G.transpose() * PG;
    const Eigen::LLT<Eigen::MatrixXd> llt(S);
    const Eigen::MatrixXd Kk = llt.solve(PG.transpose() * Phi);
    const Eigen::VectorXd Pd_s = P * dm.d[j] + s;
    r.K[j] = Kk;
    r.feedforward.row(static_cast<Eigen::Index>(j)) = (-llt.solve(G.transpose() * Pd_s)).transpose();
    const Eigen::MatrixXd Acl = Phi - G * Kk;
    s = Acl.transpose() * Pd_s;  // eq. 12.5
    P = Q * Ts + Phi.transpose() * P * Acl;
    P = 0.5 * (P + P.transpose());
    if (!P.allFinite()) {
      r.status = TvlqrResult::Status::IntegrationFailed;
      r.message = "the discrete Riccati recursion is not finite at t = " + std::to_string(dm.t[j]) + " s";
      return r;
    }
  }
  r.K[K] = r.K[K - 1];  // the last sample holds the previous gain (no interval follows it)
  r.feedforward.row(static_cast<Eigen::Index>(K)) = r.feedforward.row(static_cast<Eigen::Index>(K - 1));
  r.P0 = P;
  r.s0 = s;
  r.steps = static_cast<long>(K);
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
  r.status = TvlqrResult::Status::Solved;
  r.message = "solved";
  return r;
}

}  // namespace freeflex

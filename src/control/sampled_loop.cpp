// A TV-LQR or LQG law flown as a sampled-data controller on the full nonlinear model,
// with actuator gain, lag, delay and seeded noise (control/lqg.hpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "freeflex/control/lqg.hpp"
#include "freeflex/dynamics/full_model.hpp"
#include "model/commands.hpp"
#include "sim/range_check.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

std::string num(double v) { return util::format_number(v, 10); }

}  // namespace

void validate(const PlantOptions& o) {
  const std::string w = "plant options: ";
  if (!(o.actuator_gain > 0.0) || !std::isfinite(o.actuator_gain))
    throw std::invalid_argument(w + "actuator_gain = " + num(o.actuator_gain) + ", must be finite and > 0");
  if (!(o.lag_s >= 0.0) || !std::isfinite(o.lag_s))
    throw std::invalid_argument(w + "lag_s = " + num(o.lag_s) + ", must be finite and >= 0");
  if (!(o.delay_s >= 0.0) || !std::isfinite(o.delay_s))
    throw std::invalid_argument(w + "delay_s = " + num(o.delay_s) + ", must be finite and >= 0");
  for (int k = 0; k < o.process_noise_density.size(); ++k)
    if (!(o.process_noise_density(k) >= 0.0) || !std::isfinite(o.process_noise_density(k)))
      throw std::invalid_argument(w + "process_noise_density(" + std::to_string(k) +
                                  ") = " + num(o.process_noise_density(k)) + ", must be finite and >= 0");
}

void validate(const SampledLoopOptions& o) {
  const std::string w = "sampled-loop options: ";
  if (!(o.sample_rate_hz > 0.0) || !std::isfinite(o.sample_rate_hz))
    throw std::invalid_argument(w + "sample_rate_hz = " + num(o.sample_rate_hz) + ", must be finite and > 0");
  if (!(o.t_end >= 0.0) || !std::isfinite(o.t_end))
    throw std::invalid_argument(w + "t_end = " + num(o.t_end) + ", must be finite and >= 0");
  if (!(o.output_step_s >= 0.0) || !std::isfinite(o.output_step_s))
    throw std::invalid_argument(w + "output_step_s = " + num(o.output_step_s) + ", must be finite and >= 0");
  for (int k = 0; k < o.limits.size(); ++k)
    if (!(o.limits(k) > 0.0)) throw std::invalid_argument(w + "limits(" + std::to_string(k) + ") = " + num(o.limits(k)) + ", must be > 0");
  validate(o.integrator);
}

SampledLoopResult simulate_sampled_loop(const FlexibleBody& plant, const FirstOrderModel& model,
                                        const Excitation& loads, const ActuatorCommandFunction& u0,
                                        const TvlqrResult& law, const KalmanResult* filter,
                                        const std::vector<Sensor>& sensors, const PlantOptions& po,
                                        const SampledLoopOptions& o) {
  const std::string where = "simulate_sampled_loop";
  validate(po);
  validate(o);
  const FlexibleBody& body = model.body();
  const int N = body.dofs(), nx = 2 * N, m = model.input_size(), ne = static_cast<int>(body.elements().size());
  auto fail = [&](const std::string& what) { throw std::invalid_argument(where + ": " + what); };
  if (plant.dofs() != N || static_cast<int>(plant.elements().size()) != ne)
    fail("the plant must have the model's dofs (" + std::to_string(N) + ") and elements (" + std::to_string(ne) + ")");
  if (!law.ok() || law.K.empty()) fail("the TV-LQR law was not solved ('" + law.message + "')");
  if (law.K.front().rows() != m || law.K.front().cols() != nx) fail("the law's gains do not match the model");
  if (static_cast<int>(loads.profiles.size()) != ne) fail("expected a load profile slot per element");
  if (o.limits.size() != 0 && o.limits.size() != m) fail("expected " + std::to_string(m) + " limits (or none)");
  if (po.process_noise_density.size() != 0 && po.process_noise_density.size() != m)
    fail("expected " + std::to_string(m) + " process noise densities (or none)");
  const bool lqg = o.feedback == SampledLoopOptions::Feedback::Lqg;
  const double Ts = 1.0 / o.sample_rate_hz;
  const double t_end = o.t_end > 0.0 ? o.t_end : law.t.back();
  const std::vector<double> ts = sample_times(0.0, t_end, o.sample_rate_hz);
  const int K = static_cast<int>(ts.size()) - 1;
  Eigen::MatrixXd C;
  Eigen::VectorXd sigma_v;
  if (lqg) {
    if (!filter || !filter->ok()) fail("LQG needs a solved Kalman filter");
    if (filter->model.t.size() < ts.size() || std::abs(filter->model.t[1] - filter->model.t[0] - Ts) > 1e-9 * Ts)
      fail("the filter must be designed at sample_rate_hz = " + num(o.sample_rate_hz) + " from 0 over [0, t_end]");
    C = output_matrix(plant, sensors);
    if (C.rows() != filter->C.rows()) fail("the sensors do not match the filter's C");
    sigma_v = measurement_variance(sensors, o.sample_rate_hz).cwiseSqrt();
  }
  int delay_samples = 0;
  if (o.delay_known) {
    if (!lqg) fail("delay_known needs LQG feedback (the prediction runs on the filter's model)");
    const double d = po.delay_s / Ts;
    delay_samples = static_cast<int>(std::lround(d));
    if (std::abs(d - delay_samples) > 1e-6) fail("delay_known needs delay_s a whole number of samples, got " + num(d));
  }
  int out_every = 1;
  if (o.output_step_s > 0.0) {
    const double r = o.output_step_s / Ts;
    out_every = static_cast<int>(std::lround(r));
    if (out_every < 1 || std::abs(r - out_every) > 1e-6) fail("output_step_s must be a multiple of the sample period");
  }

  const auto clock0 = std::chrono::steady_clock::now();
  const RigidTrajectory& nom = model.nominal();
  const FullModel full(plant);
  FullModel::Data data = full.create_data();
  const bool lag = po.lag_s > 0.0;
  const int dim = nx + (lag ? m : 0);
  NormalStream noise(po.seed);
  const Eigen::VectorXd w_sigma =
      po.process_noise_density.size() ? Eigen::VectorXd(po.process_noise_density / std::sqrt(Ts)) : Eigen::VectorXd::Zero(m);

  // Commands in flight: command j (total u0 + u1) acts from ts[j] + delay on; before the
  // first arrives the actuators give nothing.
  std::vector<Eigen::VectorXd> sent;
  sent.reserve(ts.size());
  Eigen::VectorXd w = Eigen::VectorXd::Zero(m);  // process noise of the current sample
  auto applied_at = [&](double t) -> Eigen::VectorXd {
    // the latest j with ts[j] + delay <= t (sent so far)
    const double tc = t - po.delay_s;
    if (sent.empty() || tc < ts[0] - 1e-12 * Ts) return Eigen::VectorXd::Zero(m);
    int j = std::min(static_cast<int>(std::floor(tc / Ts + 1e-9)), static_cast<int>(sent.size()) - 1);
    j = std::max(j, 0);
    return sent[static_cast<std::size_t>(j)];
  };

  OdeSystem sys;
  sys.dim = dim;
  Eigen::VectorXd c(ne);
  sys.rhs = [&](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> xd) {
    detail::evaluate_commands(loads, at, c);
    const Eigen::VectorXd u = po.actuator_gain * applied_at(at.piece_mid);
    for (int k = 0; k < m; ++k) c(model.inputs()[k]) += (lag ? x(nx + k) : u(k)) + w(k);
    if (!full.rhs(data, x.head(nx), c)) return false;
    xd.head(nx) = data.x_dot;
    if (lag) xd.tail(m) = (u - x.tail(m)) / po.lag_s;
    return true;
  };
  sys.last_error = detail::mass_matrix_failure(plant);

  auto nominal_state = [&](double t) {
    const RigidState s = nom.at(Instant::at(t));
    Eigen::VectorXd x0 = Eigen::VectorXd::Zero(nx);
    x0.head<3>() = s.pos;
    x0.segment<3>(N) = s.vel;
    return x0;
  };

  SampledLoopResult r;
  std::vector<int> rows;
  for (int k = 0; k <= K; ++k)
    if (k % out_every == 0 || k == K) rows.push_back(k);
  const int T = static_cast<int>(rows.size());
  r.t.resize(T);
  r.z.resize(T, N);
  r.z_dot.resize(T, N);
  r.commands.resize(T, m);
  if (lqg) r.estimate_error.resize(T, nx);

  Eigen::VectorXd x = Eigen::VectorXd::Zero(dim);
  x.head(nx) = nominal_state(0.0);
  Eigen::VectorXd xhat = Eigen::VectorXd::Zero(nx);  // prior estimate of x1 at the current sample
  std::vector<Eigen::VectorXd> u1_sent;               // u1 of each sample, for the filter
  std::vector<double> cuts = loads.breakpoints();
  // The perturbation input acting over [t_j, t_{j+1}] as the filter knows it: the command
  // sent delay_samples before (with an unknown delay, 0: the one just sent), and before
  // the first arrives nothing, i.e. −u0.
  auto acting_u1 = [&](int j) -> Eigen::VectorXd {
    const int src = j - delay_samples;
    if (src >= 0) return u1_sent[static_cast<std::size_t>(src)];
    Eigen::VectorXd u = Eigen::VectorXd::Zero(m);
    if (u0) u0(Instant::at(ts[static_cast<std::size_t>(j)]), u);
    return -u;
  };
  int row = 0;
  for (int k = 0; k <= K; ++k) {
    const double t = ts[static_cast<std::size_t>(k)];
    const Eigen::VectorXd x1 = x.head(nx) - nominal_state(t);
    Eigen::VectorXd x_fb = x1;
    if (lqg) {
      Eigen::VectorXd y = C * x.head(nx);
      if (po.measurement_noise)
        for (int i = 0; i < y.size(); ++i) y(i) += sigma_v(i) * noise.next();
      xhat = filter->update(k, xhat, y - filter->C * nominal_state(t));
      x_fb = xhat;
    }
    for (int i = 0; i < m; ++i) w(i) = w_sigma(i) > 0.0 ? w_sigma(i) * noise.next() : 0.0;
    // the law at the time the command will act (known delay: predicted on the model)
    int k_act = k;
    Eigen::VectorXd x_act = x_fb;
    if (delay_samples > 0) {
      for (int j = k; j < k + delay_samples && j < K; ++j) {
        const Eigen::VectorXd u = acting_u1(j);  // the command acting over [t_j, t_{j+1}]
        x_act = filter->predict(j, x_act, u);
        k_act = j + 1;
      }
    }
    const double t_act = ts[static_cast<std::size_t>(k_act)];
    Eigen::VectorXd u0v = Eigen::VectorXd::Zero(m);
    if (u0) u0(Instant::at(t_act), u0v);
    Eigen::VectorXd total = u0v + law.control(t_act, x_act);
    if (o.limits.size())
      for (int i = 0; i < m; ++i) total(i) = std::clamp(total(i), -o.limits(i), o.limits(i));
    sent.push_back(total);
    u1_sent.push_back(total - u0v);
    if (row < T && rows[static_cast<std::size_t>(row)] == k) {
      r.t(row) = t;
      r.z.row(row) = x.head(N).transpose();
      r.z_dot.row(row) = x.segment(N, N).transpose();
      r.commands.row(row) = total.transpose();
      if (lqg) r.estimate_error.row(row) = (x1 - xhat).transpose();
      ++row;
    }
    if (k == K) break;
    if (lqg) {
      // the perturbation input over [t_k, t_{k+1}] as the filter knows it
      xhat = filter->predict(k, xhat, acting_u1(k));
    }
    const double t1 = ts[static_cast<std::size_t>(k + 1)];
    std::vector<double> piece_cuts;
    for (double b : cuts)
      if (b > t && b < t1) piece_cuts.push_back(b);
    if (po.delay_s > 0.0) {  // a command arrives inside the interval
      const double j = std::floor((t - po.delay_s) / Ts + 1e-9) + 1.0;
      const double arrive = j * Ts + po.delay_s;
      if (arrive > t && arrive < t1 && !roundoff_span(t, arrive) && !roundoff_span(arrive, t1)) piece_cuts.push_back(arrive);
    }
    const IntegrationResult ir = integrate(sys, x, {t, t1}, piece_cuts, o.integrator);
    r.rhs_evaluations += ir.rhs_evaluations;
    if (!ir.ok()) {
      r.status = IntegrationStatus::Failed;
      r.message = "the plant's integration failed over [" + num(t) + ", " + num(t1) + "] s: " + ir.message;
      r.t.conservativeResize(row);
      r.z.conservativeResize(row, N);
      r.z_dot.conservativeResize(row, N);
      r.commands.conservativeResize(row, m);
      if (lqg) r.estimate_error.conservativeResize(row, nx);
      r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
      return r;
    }
    x = ir.x.row(ir.x.rows() - 1).transpose();
  }
  r.status = IntegrationStatus::Completed;
  r.message = "completed";
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
  return r;
}

}  // namespace freeflex

#pragma once
// Output feedback (docs/theory.md section 12): sensors, the time-varying Kalman filter on
// the first-order model about the nominal motion, and LQG = TV-LQR + filter, flown as a
// sampled-data (digital) controller on the full nonlinear model with seeded noise,
// actuator gain, first-order lag and pure delay.
//
// Conventions. Sensors are sampled together at f_s = 1/T_s; a white noise of intensity
// N² (E[v(t) v(s)] = N² δ(t − s), N the "noise density" in unit/√Hz) averaged over one
// sample has variance N²/T_s, the variance of each measurement here (eq. 12.2); process
// noise on the actuators' inputs is the same kind of white noise (intensity W, diagonal)
// and is simulated held over each sample (variance W/T_s). The controller computes
// u1_k = −K(t_k) x̂_k + u_ff(t_k) from the samples at t_k and the plant receives u0 + u1_k
// held from t_k + τ to t_{k+1} + τ (zero-order hold after the delay τ), times the
// actuator gain, through the lag a' = (u − a)/T_lag when T_lag > 0.
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/control/closed_loop.hpp"
#include "freeflex/control/tvlqr.hpp"
#include "freeflex/dynamics/first_order.hpp"
#include "freeflex/enum_names.hpp"
#include "freeflex/model/loads.hpp"
#include "freeflex/sim/integrator.hpp"

namespace freeflex {

/// A sensor. Every type is linear in z = [Rx, Ry, θ, q] and z', so on the first-order
/// model y = C (x0(t) + x1) with a constant C (eq. 12.1).
struct Sensor {
  enum class Type {
    GyroAttitude,     ///< θ [rad]
    GyroRate,         ///< θ' [rad/s]
    Strain,           ///< bending strain per unit distance from the neutral axis: w''(x) = Φ''(x) q [1/m]
    TipDisplacement,  ///< elastic deflection w(x) = Φ(x) q at the position [m]
  };
  std::string name;
  Type type = Type::GyroAttitude;
  double position_m = 0.0;     ///< distance from the beam's left end (strain, tip_displacement)
  double noise_density = 0.0;  ///< N [unit/√Hz], >= 0
};

/// C (p x 2N) on x = [z, z'] for the sensors, p = sensors.size(). Throws
/// std::invalid_argument for a position off the beam or a negative noise density.
Eigen::MatrixXd output_matrix(const FlexibleBody& body, const std::vector<Sensor>& sensors);
/// Variance of each sampled measurement, N²/T_s (p entries).
Eigen::VectorXd measurement_variance(const std::vector<Sensor>& sensors, double sample_rate_hz);

/// x_{k+1} = Φ_k x_k + Γ_k u_k + d_k + w_k, w_k ~ N(0, Q_k): the exact discretization of
/// x' = A x + B (u + w) + g with u held over [t_k, t_{k+1}] and w white of intensity W
/// (eq. 12.3), computed by CVODES (Φ' = AΦ, Γ' = AΓ + B, d' = A d + g,
/// Q' = AQ + QAᵀ + BWBᵀ from Φ = I, Γ = d = Q = 0 at each t_k).
struct DiscreteLtv {
  IntegrationStatus status = IntegrationStatus::Failed;
  std::string message;
  bool ok() const { return status == IntegrationStatus::Completed; }
  std::vector<double> t;  ///< t_0 .. t_K
  std::vector<Eigen::MatrixXd> Phi, Gamma, Qd;  ///< K entries each
  std::vector<Eigen::VectorXd> d;
};

struct DiscretizeOptions {
  IntegratorOptions integrator;  ///< Adams, rtol 1e-8 by default
};
void validate(const DiscretizeOptions& options);

/// Throws std::invalid_argument for fewer than two times, times not ascending, W not
/// m x m symmetric PSD.
DiscreteLtv discretize(const LtvSystem& system, const std::vector<double>& times, const Eigen::MatrixXd& W,
                       const DiscretizeOptions& options = {});

/// The time-varying Kalman filter's gains and covariances for measurements
/// y_k = C x_k + v_k, v_k ~ N(0, V), at every t_k of the discrete model (eq. 12.4):
///   P⁻_0 = P0,  L_k = P⁻_k Cᵀ (C P⁻_k Cᵀ + V)⁻¹,  P⁺_k = (I − L_k C) P⁻_k (I − L_k C)ᵀ + L_k V L_kᵀ,
///   P⁻_{k+1} = Φ_k P⁺_k Φ_kᵀ + Q_k.
struct KalmanResult {
  enum class Status { Solved, DiscretizationFailed, NotPositiveDefinite };
  Status status = Status::DiscretizationFailed;
  std::string message;
  bool ok() const { return status == Status::Solved; }
  DiscreteLtv model;
  Eigen::MatrixXd C, V;
  std::vector<Eigen::MatrixXd> P_prior, P_post, L;  ///< K + 1 entries each (k = 0 .. K)

  /// Measurement update at sample k: x̂⁺ = x̂⁻ + L_k (y − C x̂⁻).
  Eigen::VectorXd update(int k, const Eigen::Ref<const Eigen::VectorXd>& x_prior,
                         const Eigen::Ref<const Eigen::VectorXd>& y) const;
  /// Time update over [t_k, t_{k+1}] with u held: Φ_k x̂⁺ + Γ_k u + d_k.
  Eigen::VectorXd predict(int k, const Eigen::Ref<const Eigen::VectorXd>& x_post,
                          const Eigen::Ref<const Eigen::VectorXd>& u) const;
};

/// The filter of the sensors on `system` at sample rate f_s over [t0, tf] (tf − t0 a
/// multiple of T_s within 1e-9 relative, else the last interval is shorter), process
/// noise intensity W on the inputs, initial covariance P0. Throws
/// std::invalid_argument for sizes that do not match or a rate <= 0.
KalmanResult design_kalman(const LtvSystem& system, const Eigen::MatrixXd& C, const Eigen::MatrixXd& V,
                           const Eigen::MatrixXd& W, const Eigen::MatrixXd& P0, double t0, double tf,
                           double sample_rate_hz, const DiscretizeOptions& options = {});

/// The sample times t0, t0 + T_s, ..., tf.
std::vector<double> sample_times(double t0, double tf, double sample_rate_hz);

/// The digital TV-LQR (eq. 12.5): the law u_k = −K_k x_k + u_ff,k held over each sample
/// interval that minimizes Σ (x_kᵀ Q T_s x_k + u_kᵀ R T_s u_k) + x_Kᵀ Qf x_K on the discrete
/// model (the continuous cost sampled), by the backward Riccati recursion
///   K_k = (R T_s + Γᵀ P Γ)⁻¹ Γᵀ P Φ,  P_k = Q T_s + Φᵀ P (Φ − Γ K_k),
///   u_ff,k = −(R T_s + Γᵀ P Γ)⁻¹ Γᵀ (P d + s),  s_k = (Φ − Γ K_k)ᵀ (P d + s),
/// with P = P_{k+1}, s = s_{k+1}: the optimal law for commands that are held, where the
/// continuous law's gains read at the samples are an approximation that degrades as the
/// sample rate nears its closed-loop bandwidth (its fastest poles, −8.6e3 1/s on the
/// paper's beam, are beyond any practical sampler). The result's grid is the sample times
/// (gain(t) is exact at them). Throws std::invalid_argument for sizes that do not
/// match, Q or Qf not PSD, R not PD.
TvlqrResult solve_discrete_tvlqr(const DiscreteLtv& model, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& R,
                                 const Eigen::MatrixXd& Qf);

/// The plant's departures from the model the controller was designed on, and the noise.
struct PlantOptions {
  double actuator_gain = 1.0;  ///< commands reach the structure times this, > 0
  double lag_s = 0.0;          ///< actuator first-order time constant, >= 0 (0: none)
  double delay_s = 0.0;        ///< pure delay of the commands, >= 0
  Eigen::VectorXd process_noise_density;  ///< per actuator [N/√Hz or N m/√Hz]; empty: none
  bool measurement_noise = true;          ///< add the sensors' noise to the samples
  std::uint64_t seed = 1;                 ///< of the noise (same seed, same noise)
};
void validate(const PlantOptions& options);

/// The controller: full state (the exact sampled state, as the continuous TV-LQR sees
/// it) or LQG (the Kalman filter's estimate from the sensors).
struct SampledLoopOptions {
  enum class Feedback { FullState, Lqg } feedback = Feedback::FullState;
  double sample_rate_hz = 1000.0;  ///< > 0
  /// The controller knows the delay: it predicts the state at t_k + τ with the first-order
  /// model and the commands still on their way, and the filter uses the commands actually
  /// applied. Needs an LQG filter and τ a whole number of samples.
  bool delay_known = false;
  double t_end = 0.0;       ///< [s]; 0: the law's tf
  double output_step_s = 0.0;  ///< rows of the result every this [s] (a multiple of T_s); 0: every sample
  Eigen::VectorXd limits;   ///< |u0 + u1| <= limits(k); empty: none
  IntegratorOptions integrator;  ///< of the plant between samples (Adams: the plant is not stiff here)
};
void validate(const SampledLoopOptions& options);

struct SampledLoopResult {
  IntegrationStatus status = IntegrationStatus::Failed;
  std::string message;
  bool ok() const { return status == IntegrationStatus::Completed; }
  Eigen::VectorXd t;
  Eigen::MatrixXd z, z_dot;   ///< plant totals, one row per output time
  Eigen::MatrixXd commands;   ///< computed u0 + u1 (before gain, delay, lag)
  Eigen::MatrixXd estimate_error;  ///< LQG only: x1 − x̂ at each output time (perturbation coordinates)
  long rhs_evaluations = 0;
  double wall_time_s = 0.0;
};

/// The law (and filter, for LQG) designed on `model` flown on the full nonlinear model
/// of `plant` (same elements and dofs as model.body(): EI, masses, damping may differ).
/// Loads and u0 as in simulate_closed_loop_full. For LQG `filter` must have been
/// designed at options.sample_rate_hz from t = 0 over at least [0, t_end]. Throws
/// std::invalid_argument for mismatched sizes or options out of range.
SampledLoopResult simulate_sampled_loop(const FlexibleBody& plant, const FirstOrderModel& model,
                                        const Excitation& loads, const ActuatorCommandFunction& u0,
                                        const TvlqrResult& law, const KalmanResult* filter,
                                        const std::vector<Sensor>& sensors, const PlantOptions& plant_options,
                                        const SampledLoopOptions& options);

/// Deterministic standard normal numbers from a 64-bit seed (splitmix64 + Box–Muller):
/// the same sequence on every platform and standard library.
class NormalStream {
 public:
  explicit NormalStream(std::uint64_t seed) : state_(seed) {}
  double next();

 private:
  std::uint64_t bits();
  std::uint64_t state_;
  bool have_spare_ = false;
  double spare_ = 0.0;
};

template <>
struct EnumNames<Sensor::Type> {
  static constexpr const char* what = "sensor type";
  static constexpr std::array<std::pair<Sensor::Type, const char*>, 4> names{
      {{Sensor::Type::GyroAttitude, "gyro_attitude"},
       {Sensor::Type::GyroRate, "gyro_rate"},
       {Sensor::Type::Strain, "strain"},
       {Sensor::Type::TipDisplacement, "tip_displacement"}}};
};

template <>
struct EnumNames<KalmanResult::Status> {
  static constexpr const char* what = "Kalman filter status";
  static constexpr std::array<std::pair<KalmanResult::Status, const char*>, 3> names{
      {{KalmanResult::Status::Solved, "solved"},
       {KalmanResult::Status::DiscretizationFailed, "discretization_failed"},
       {KalmanResult::Status::NotPositiveDefinite, "not_positive_definite"}}};
};

template <>
struct EnumNames<SampledLoopOptions::Feedback> {
  static constexpr const char* what = "feedback";
  static constexpr std::array<std::pair<SampledLoopOptions::Feedback, const char*>, 2> names{
      {{SampledLoopOptions::Feedback::FullState, "full_state"}, {SampledLoopOptions::Feedback::Lqg, "lqg"}}};
};

}  // namespace freeflex

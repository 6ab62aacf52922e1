#pragma once
// Loads and actuators (docs/theory.md section 6): point forces with inertial components,
// thrusters fixed to the body (optionally following the local slope), point torques.
// Each is a "force element" whose scalar command (N or N m) scales a direction; a load
// takes its command from a time profile, an actuator from a controller.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/enum_names.hpp"
#include "freeflex/model/instant.hpp"

namespace freeflex {

/// A command as a function of time: piecewise-constant steps or piecewise-linear, zero
/// outside [times.front(), times.back()].
class TimeProfile {
 public:
  enum class Kind { Steps, Linear };
  /// Steps: values[i] on [times[i], times[i+1]) (the last one closed); values.size() ==
  /// times.size() - 1. Linear: values at the times, interpolated; same sizes.
  /// Throws std::invalid_argument if times are not strictly ascending or sizes disagree.
  TimeProfile(Kind kind, std::vector<double> times, std::vector<double> values);

  /// Value with the formula of the piece containing piece_mid (see Instant).
  double value(const Instant& at) const;
  double value(double t) const { return value(Instant::at(t)); }
  Kind kind() const { return kind_; }
  const std::vector<double>& times() const { return times_; }
  const std::vector<double>& values() const { return values_; }

 private:
  Kind kind_;
  std::vector<double> times_, values_;
};

/// Where and how a command acts on the beam.
struct ForceElement {
  enum class Type {
    Force,     ///< point force, direction in inertial axes X, Y
    Thruster,  ///< point force, direction in body axes x, y (follows theta)
    Torque,    ///< point torque about the plane's normal; direction unused
  };
  std::string name;
  Type type = Type::Force;
  double position_m = 0.0;                     ///< distance from the left end
  Eigen::Vector2d direction{0.0, 1.0};         ///< force per unit command
  bool follow_slope = false;                   ///< thruster turns with the local slope theta + u'
};

/// The commands of every force element over time: element e follows profiles[e] when it
/// has one (a load) and is zero otherwise (an actuator without a controller).
struct Excitation {
  std::vector<std::optional<TimeProfile>> profiles;
  /// Optional commands added on top of the profiles (e.g. an optimized maneuver driving
  /// the actuators), with the times where they may jump or kink and when they end. A
  /// callback: it adds into the buffer of every element's commands it is handed.
  std::function<void(const Instant&, Eigen::Ref<Eigen::VectorXd>)> add_commands;
  std::vector<double> add_breakpoints;
  double add_end_time = 0.0;
  /// commands(e) for every element (profiles.size() entries).
  Eigen::VectorXd commands(const Instant& at) const;
  /// Every profile time: where some command may jump or kink.
  std::vector<double> breakpoints() const;
  /// Latest profile time (0 if there is none): no load acts after it.
  double end_time() const;
};

template <>
struct EnumNames<TimeProfile::Kind> {
  static constexpr const char* what = "profile type";
  static constexpr std::array<std::pair<TimeProfile::Kind, const char*>, 2> names{
      {{TimeProfile::Kind::Steps, "steps"}, {TimeProfile::Kind::Linear, "linear"}}};
};

template <>
struct EnumNames<ForceElement::Type> {
  static constexpr const char* what = "force element type";
  static constexpr std::array<std::pair<ForceElement::Type, const char*>, 3> names{
      {{ForceElement::Type::Force, "force"}, {ForceElement::Type::Thruster, "thruster"},
       {ForceElement::Type::Torque, "torque"}}};
};

}  // namespace freeflex

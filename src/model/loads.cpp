// Loads and actuators: time profiles, and every element's commands at an instant.
#include "freeflex/model/loads.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "model/commands.hpp"

namespace freeflex {

TimeProfile::TimeProfile(Kind kind, std::vector<double> times, std::vector<double> values)
    : kind_(kind), times_(std::move(times)), values_(std::move(values)) {
  if (times_.size() < 2) throw std::invalid_argument("time profile: at least two times are required");
  for (std::size_t i = 1; i < times_.size(); ++i)
    if (!(times_[i] > times_[i - 1]))
      throw std::invalid_argument("time profile: times must be strictly ascending (entry " + std::to_string(i + 1) +
                                  ")");
  const std::size_t expect = kind_ == Kind::Steps ? times_.size() - 1 : times_.size();
  if (values_.size() != expect)
    throw std::invalid_argument("time profile: expected " + std::to_string(expect) + " values, got " +
                                std::to_string(values_.size()));
}

double TimeProfile::value(const Instant& at) const {
  const double mid = at.piece_mid;
  if (mid < times_.front() || mid > times_.back()) return 0.0;
  std::size_t i = 0;
  while (i + 2 < times_.size() && mid >= times_[i + 1]) ++i;
  if (kind_ == Kind::Steps) return values_[i];
  const double s = (at.t - times_[i]) / (times_[i + 1] - times_[i]);
  return values_[i] + s * (values_[i + 1] - values_[i]);
}

void detail::evaluate_commands(const Excitation& ex, const Instant& at, Eigen::Ref<Eigen::VectorXd> commands) {
  for (std::size_t e = 0; e < ex.profiles.size(); ++e)
    commands(static_cast<Eigen::Index>(e)) = ex.profiles[e] ? ex.profiles[e]->value(at) : 0.0;
  if (ex.add_commands) ex.add_commands(at, commands);
}

Eigen::VectorXd Excitation::commands(const Instant& at) const {
  Eigen::VectorXd c(static_cast<Eigen::Index>(profiles.size()));
  detail::evaluate_commands(*this, at, c);
  return c;
}

std::vector<double> Excitation::breakpoints() const {
  std::vector<double> b = add_breakpoints;
  for (const auto& p : profiles)
    if (p) b.insert(b.end(), p->times().begin(), p->times().end());
  return b;
}

double Excitation::end_time() const {
  double t = add_commands ? add_end_time : 0.0;
  for (const auto& p : profiles)
    if (p) t = std::max(t, p->times().back());
  return t;
}

}  // namespace freeflex

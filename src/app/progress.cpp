// Progress lines of a long phase (app/progress.hpp).
#include "freeflex/app/progress.hpp"

#include <algorithm>
#include <chrono>

#include "util/format.hpp"

namespace freeflex {

namespace {
double wall_s() {
  using clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}
}  // namespace

ProgressReport::ProgressReport(std::ostream* log, double total_s, double every_s)
    : log_(log), total_s_(total_s), every_s_(every_s), start_(wall_s()), next_(start_ + every_s) {}

void ProgressReport::update(double t) {
  if (!log_) return;
  const double now = wall_s();
  if (now < next_) return;
  schedule(now);
  const double pct = total_s_ > 0.0 ? 100.0 * t / total_s_ : 100.0;
  *log_ << (printed_ ? "" : "\n") << "  " << util::format_number(t, 4) << " of " << util::format_number(total_s_, 6)
        << " s (" << static_cast<int>(pct) << "%) after " << static_cast<int>(now - start_) << " s\n"
        << std::flush;
  printed_ = true;
}

void ProgressReport::note(const std::string& what) {
  if (!log_) return;
  const double now = wall_s();
  if (now < next_) return;
  schedule(now);
  *log_ << (printed_ ? "" : "\n") << "  " << what << " after " << static_cast<int>(now - start_) << " s\n"
        << std::flush;
  printed_ = true;
}

void ProgressReport::schedule(double now) {
  // sparser as the phase goes on; every_s = 0 prints every call
  next_ = every_s_ > 0.0 ? now + std::max(every_s_, 0.25 * (now - start_)) : now;
}

std::function<void(double)> ProgressReport::callback() {
  return [this](double t) { update(t); };
}

}  // namespace freeflex

#pragma once
// Progress of a long phase on a log stream: a line at most every few seconds of wall time.
#include <functional>
#include <ostream>
#include <string>

namespace freeflex {

/// How far a long phase has got, on the log: a line at most every `every_s` seconds of
/// wall time ("  4.2 of 20 s (21%) after 6 s"), none if the phase ends sooner.
class ProgressReport {
 public:
  /// `every_s` = 0: a line for every call (for tests).
  ProgressReport(std::ostream* log, double total_s, double every_s = 2.0);
  /// The phase has covered `t` seconds of simulated time out of `total_s`.
  void update(double t);
  /// For phases without a known end: "  <what> after 6 s", at the same pace as update().
  void note(const std::string& what);
  /// update() as a callback (IntegratorOptions::progress); this object must outlive it.
  std::function<void(double)> callback();
  /// What to print before the phase's closing words: a new indented line if progress
  /// lines were printed, nothing otherwise.
  const char* resume() const { return printed_ ? "  " : ""; }

 private:
  void schedule(double now);  ///< sets when the next line is due

  std::ostream* log_;
  double total_s_, every_s_;
  double start_, next_;
  bool printed_ = false;
};

}  // namespace freeflex

#pragma once
// Running an external program (gnuplot) under a time limit: fork and exec, no shell, in
// its own process group, which is killed whole when the limit passes. Private to src/.
#include <cstddef>
#include <string>
#include <vector>

namespace freeflex::io_detail {

struct ProgramRun {
  enum class Status { Exited, Signaled, TimedOut, NotStarted };
  Status status = Status::NotStarted;
  int exit_code = -1;   ///< with Exited
  int signal = 0;       ///< with Signaled
  std::string output;   ///< stdout and stderr together, at most the first max_output bytes
  std::string error;    ///< why it did not start (NotStarted)
  double seconds = 0;   ///< wall time until it ended or was killed
  bool ok() const { return status == Status::Exited && exit_code == 0; }
};

/// Runs argv[0] (a path; not looked up in PATH) with arguments argv[1..] in directory
/// `cwd`, stdin from /dev/null. Past `timeout_s` seconds of wall time the program's whole
/// process group gets SIGTERM, then SIGKILL a second later, and the result is TimedOut.
/// Once the program has exited, what it left running in its group is killed too.
ProgramRun run_program(const std::vector<std::string>& argv, const std::string& cwd, double timeout_s,
                       std::size_t max_output = 16384);

}  // namespace freeflex::io_detail

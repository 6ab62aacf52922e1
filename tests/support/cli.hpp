#pragma once
// Runs the freeflex program built beside the tests and captures its output and exit code.
#include <cstdio>
#include <fstream>
#include <string>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace freeflex_test {

struct CliResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together (unless redirected otherwise)
};

/// `redirect`: what the shell does with the streams (default: stderr into stdout; both
/// are captured).
inline CliResult run_cli(const std::string& args, const std::string& redirect = "2>&1") {
  const std::string cmd = std::string("'") + FREEFLEX_CLI + "' " + args + " " + redirect;
  CliResult r;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p)) r.output += buf;
  const int st = ::pclose(p);
  r.exit_code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

/// A fresh temporary directory path (not created).
inline std::string temp_path(const std::string& stem) {
  static int counter = 0;
  return "/tmp/freeflex_test_" + stem + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
}

inline std::string write_temp(const std::string& stem, const std::string& text) {
  const std::string path = temp_path(stem) + ".toml";
  std::ofstream(path) << text;
  return path;
}

inline bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

}  // namespace freeflex_test

// An external program under a time limit (io/run_program.hpp): fork, exec without a
// shell, its output read through a pipe with poll(), its process group killed on time-out.
#include "io/run_program.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>

#include <fcntl.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

namespace freeflex::io_detail {
namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

/// True once `pid` has ended. It is not reaped: while it is a zombie its process group
/// id cannot be reused, so the group can still be killed safely.
bool has_ended(pid_t pid) {
  siginfo_t info{};
  info.si_pid = 0;
  return ::waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT) == 0 && info.si_pid == pid;
}

/// Waits up to `seconds` for `pid` to end (not reaping it); true if it did.
bool wait_for(pid_t pid, double seconds) {
  const auto until = Clock::now() + std::chrono::duration<double>(seconds);
  while (!has_ended(pid)) {
    if (Clock::now() >= until) return false;
    ::usleep(10000);
  }
  return true;
}

/// Kills what is left of the group led by `pid` and reaps `pid`; its wait status.
int kill_group_and_reap(pid_t pid) {
  ::kill(-pid, SIGKILL);  // nothing the program started outlives it (ESRCH when none is left)
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}

}  // namespace

ProgramRun run_program(const std::vector<std::string>& argv, const std::string& cwd, double timeout_s,
                       std::size_t max_output) {
  ProgramRun run;
  if (argv.empty() || argv[0].empty()) {
    run.error = "no program given";
    return run;
  }
  // everything the child needs is built before fork: after it, only async-signal-safe calls
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  int out[2], exec_error[2];
  if (::pipe2(out, O_CLOEXEC) != 0) {
    run.error = std::string("cannot create a pipe: ") + std::strerror(errno);
    return run;
  }
  if (::pipe2(exec_error, O_CLOEXEC) != 0) {
    run.error = std::string("cannot create a pipe: ") + std::strerror(errno);
    ::close(out[0]);
    ::close(out[1]);
    return run;
  }
  const auto start = Clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) {
    run.error = std::string("cannot fork: ") + std::strerror(errno);
    for (int fd : {out[0], out[1], exec_error[0], exec_error[1]}) ::close(fd);
    return run;
  }
  if (pid == 0) {  // the child: its own process group, output into the pipe, then exec
    ::setpgid(0, 0);
    int err = 0;
    const int null_in = ::open("/dev/null", O_RDONLY);
    if (null_in < 0 || ::dup2(null_in, 0) < 0 || ::dup2(out[1], 1) < 0 || ::dup2(out[1], 2) < 0) err = errno;
    if (!err && !cwd.empty() && ::chdir(cwd.c_str()) != 0) err = errno;
    if (!err) {
      ::signal(SIGPIPE, SIG_DFL);
      ::execv(args[0], args.data());
      err = errno;
    }
    const ssize_t ignored = ::write(exec_error[1], &err, sizeof err);
    (void)ignored;
    ::_exit(127);
  }
  ::setpgid(pid, pid);  // also here: no race with the kill below
  ::close(out[1]);
  ::close(exec_error[1]);
  int child_errno = 0;
  ssize_t got;
  do got = ::read(exec_error[0], &child_errno, sizeof child_errno);
  while (got < 0 && errno == EINTR);
  ::close(exec_error[0]);
  int status = 0;
  if (got == static_cast<ssize_t>(sizeof child_errno)) {  // exec (or the set-up before it) failed
    ::close(out[0]);
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    run.error = "cannot run '" + argv[0] + "': " + std::strerror(child_errno);
    run.seconds = since(start);
    return run;
  }

  bool exited = false, timed_out = false;
  bool open = true;
  char buf[4096];
  while (!exited) {
    const double left = timeout_s - since(start);
    if (left <= 0) {
      timed_out = true;
      break;
    }
    if (open) {
      pollfd p{out[0], POLLIN, 0};
      const int wait_ms = static_cast<int>(std::min(left * 1000.0, 50.0)) + 1;
      const int n = ::poll(&p, 1, wait_ms);
      if (n > 0) {
        const ssize_t r = ::read(out[0], buf, sizeof buf);
        if (r > 0 && run.output.size() < max_output)
          run.output.append(buf, std::min<std::size_t>(static_cast<std::size_t>(r), max_output - run.output.size()));
        if (r == 0 || (r < 0 && errno != EINTR && errno != EAGAIN)) open = false;  // every writer has closed it
      }
    } else {
      ::usleep(10000);
    }
    exited = has_ended(pid);
  }
  if (timed_out) {
    ::close(out[0]);
    ::kill(-pid, SIGTERM);
    wait_for(pid, 1.0);
    kill_group_and_reap(pid);
    run.status = ProgramRun::Status::TimedOut;
    run.seconds = since(start);
    return run;
  }
  if (open) {  // what it wrote just before it ended; a program it left running may hold the pipe
    ::fcntl(out[0], F_SETFL, O_NONBLOCK);
    ssize_t r;
    while ((r = ::read(out[0], buf, sizeof buf)) > 0)
      if (run.output.size() < max_output)
        run.output.append(buf, std::min<std::size_t>(static_cast<std::size_t>(r), max_output - run.output.size()));
  }
  ::close(out[0]);
  status = kill_group_and_reap(pid);
  run.seconds = since(start);
  if (WIFEXITED(status)) {
    run.status = ProgramRun::Status::Exited;
    run.exit_code = WEXITSTATUS(status);
  } else {
    run.status = ProgramRun::Status::Signaled;
    run.signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
  }
  return run;
}

}  // namespace freeflex::io_detail

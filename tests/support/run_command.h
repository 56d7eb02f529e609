// Runs a program and captures its exit code, stdout and stderr, for end-to-end tests
// of the shtool executable (and of scripts). Self-contained, header-only, POSIX.
//
// fork/exec with one pipe per stream rather than popen: popen gives only one stream,
// and a shell in between would make quoting of arguments (directions such as "-1,0,0",
// file names with spaces) part of every test. Both pipes are drained together with
// poll(), so a child that writes a lot to one stream cannot block on the other.
#pragma once

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <stdexcept>
#include <cstdint>
#include <string>
#include <vector>

#include <fcntl.h>
#include <poll.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <sys/resource.h>
#include <unistd.h>

namespace shtool::test {

struct CommandResult {
  // The exit status of a normally exiting child; 128 + signal number if it was killed
  // by a signal (the shell's convention), so a crash is never mistaken for success.
  int exit_code = -1;
  std::string out;  // everything written to stdout
  std::string err;  // everything written to stderr
  bool signaled = false;
  int signal = 0;
  bool timed_out = false;  // killed by run_command because it exceeded the timeout
};

struct CommandOptions {
  std::string stdin_data;            // written to the child's stdin, then stdin is closed
  bool no_stdin = false;             // the child starts with file descriptor 0 closed
  double timeout_seconds = 0.0;      // <= 0: no timeout
  std::string working_directory;     // empty: inherit
  // The child's address space limit (RLIMIT_AS) in bytes; 0: none. A sanitizer's shadow
  // memory needs terabytes of address space: the caller leaves it 0 there.
  std::uint64_t address_space_bytes = 0;
};

namespace detail {

[[noreturn]] inline void throw_errno(const std::string& what) {
  throw std::runtime_error("run_command: " + what + ": " + std::strerror(errno));
}

}  // namespace detail

// Runs argv[0] (looked up in PATH if it has no slash) with arguments argv[1..].
// Throws std::runtime_error only when the child cannot be started at all; a program
// that exits non-zero is a normal result.
inline CommandResult run_command(const std::vector<std::string>& argv,
                                 const CommandOptions& options = {}) {
  if (argv.empty()) throw std::runtime_error("run_command: empty argv");

  int in_pipe[2], out_pipe[2], err_pipe[2], exec_pipe[2];
  if (pipe2(in_pipe, O_CLOEXEC) != 0) detail::throw_errno("pipe");
  if (pipe2(out_pipe, O_CLOEXEC) != 0) detail::throw_errno("pipe");
  if (pipe2(err_pipe, O_CLOEXEC) != 0) detail::throw_errno("pipe");
  // Closed by a successful exec (O_CLOEXEC); receives errno if exec fails, so "no such
  // program" is reported as an error instead of as a mysterious exit code.
  if (pipe2(exec_pipe, O_CLOEXEC) != 0) detail::throw_errno("pipe");

  std::vector<char*> cargv;
  for (const std::string& a : argv) cargv.push_back(const_cast<char*>(a.c_str()));
  cargv.push_back(nullptr);

  const pid_t pid = fork();
  if (pid < 0) detail::throw_errno("fork");
  if (pid == 0) {
    // Child: only async-signal-safe calls from here on.
    if (options.no_stdin)
      close(STDIN_FILENO);
    else
      dup2(in_pipe[0], STDIN_FILENO);
    dup2(out_pipe[1], STDOUT_FILENO);
    dup2(err_pipe[1], STDERR_FILENO);
    if (options.address_space_bytes) {
      const struct rlimit limit = {options.address_space_bytes, options.address_space_bytes};
      setrlimit(RLIMIT_AS, &limit);
    }
    if (!options.working_directory.empty() && chdir(options.working_directory.c_str()) != 0) {
      const int e = errno;
      (void)!write(exec_pipe[1], &e, sizeof e);
      _exit(127);
    }
    execvp(cargv[0], cargv.data());
    const int e = errno;
    (void)!write(exec_pipe[1], &e, sizeof e);
    _exit(127);
  }

  close(in_pipe[0]);
  close(out_pipe[1]);
  close(err_pipe[1]);
  close(exec_pipe[1]);

  int exec_errno = 0;
  ssize_t n;
  do n = read(exec_pipe[0], &exec_errno, sizeof exec_errno);
  while (n < 0 && errno == EINTR);
  close(exec_pipe[0]);

  CommandResult result;
  // A child that exits without reading its stdin must not kill the test with SIGPIPE.
  struct sigaction ignore {}, previous {};
  ignore.sa_handler = SIG_IGN;
  sigaction(SIGPIPE, &ignore, &previous);

  int in_fd = in_pipe[1];
  std::size_t in_written = 0;
  if (options.stdin_data.empty()) {
    close(in_fd);
    in_fd = -1;
  }
  int out_fd = out_pipe[0], err_fd = err_pipe[0];
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration<double>(options.timeout_seconds);
  char buffer[65536];
  while (out_fd >= 0 || err_fd >= 0 || in_fd >= 0) {
    pollfd fds[3];
    int count = 0;
    if (out_fd >= 0) fds[count++] = {out_fd, POLLIN, 0};
    if (err_fd >= 0) fds[count++] = {err_fd, POLLIN, 0};
    if (in_fd >= 0) fds[count++] = {in_fd, POLLOUT, 0};
    int wait_ms = -1;
    if (options.timeout_seconds > 0) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      wait_ms = left.count() > 0 ? static_cast<int>(left.count()) : 0;
    }
    const int ready = poll(fds, count, wait_ms);
    if (ready < 0) {
      if (errno == EINTR) continue;
      detail::throw_errno("poll");
    }
    if (ready == 0) {  // timeout
      kill(pid, SIGKILL);
      result.timed_out = true;
      break;
    }
    for (int k = 0; k < count; ++k) {
      if (fds[k].revents == 0) continue;
      if (fds[k].fd == in_fd) {
        const ssize_t w = write(in_fd, options.stdin_data.data() + in_written,
                                options.stdin_data.size() - in_written);
        if (w > 0) in_written += static_cast<std::size_t>(w);
        if (w < 0 && errno != EINTR && errno != EAGAIN) in_written = options.stdin_data.size();
        if (in_written == options.stdin_data.size()) {
          close(in_fd);
          in_fd = -1;
        }
        continue;
      }
      int& fd = fds[k].fd == out_fd ? out_fd : err_fd;
      std::string& sink = fds[k].fd == out_fd ? result.out : result.err;
      const ssize_t r = read(fd, buffer, sizeof buffer);
      if (r > 0) {
        sink.append(buffer, static_cast<std::size_t>(r));
      } else if (r == 0 || (errno != EINTR && errno != EAGAIN)) {
        close(fd);
        fd = -1;
      }
    }
  }
  for (int fd : {in_fd, out_fd, err_fd})
    if (fd >= 0) close(fd);
  sigaction(SIGPIPE, &previous, nullptr);

  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) detail::throw_errno("waitpid");
  }
  if (exec_errno != 0) {
    errno = exec_errno;
    detail::throw_errno("cannot run '" + argv[0] + "'");
  }
  if (WIFEXITED(status)) {
    result.exit_code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    result.signaled = true;
    result.signal = WTERMSIG(status);
    result.exit_code = 128 + result.signal;
  }
  return result;
}

// A whole command line run by /bin/sh -c, for the occasional pipeline or redirection.
// Prefer the argv form: it needs no quoting.
inline CommandResult run_shell(const std::string& command_line,
                               const CommandOptions& options = {}) {
  return run_command({"/bin/sh", "-c", command_line}, options);
}

// "prog a b": for failure messages.
inline std::string describe_command(const std::vector<std::string>& argv) {
  std::string s;
  for (const std::string& a : argv) {
    if (!s.empty()) s += ' ';
    const bool quote = a.empty() || a.find_first_of(" \t'\"\\$`") != std::string::npos;
    s += quote ? "'" + a + "'" : a;
  }
  return s;
}

}  // namespace shtool::test

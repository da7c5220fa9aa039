// Child processes of a test: a function run in a forked child, and a program spawned as a peer.
#pragma once

#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>
#include <vector>

namespace saw::testing {

// Runs f in a forked child; its exit code, or 100 + the signal that ended it. Forked from a test
// that has threads, f should start none of its own (a proxy, a manager: under TSan such a child
// hung); a ChildProcess is for that.
template <class F>
int in_child(F f) {
  const pid_t pid = fork();
  if (pid == 0) _exit(f());
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 100 + WTERMSIG(status);
}

// A program run as a child process (argv[0] is its path; it inherits the environment). Killed
// with -9 and reaped when the handle goes: a peer that dies without a word, never one left over.
class ChildProcess {
 public:
  explicit ChildProcess(const std::vector<std::string>& argv);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // -1 if the program could not be spawned, or once it has been killed.
  pid_t pid() const noexcept { return pid_; }
  // SIGKILL, then waits for it: when this returns, the process is gone. Does nothing twice.
  void kill9() noexcept;

 private:
  pid_t pid_ = -1;
};

}  // namespace saw::testing

#include "sim_process.hpp"

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <utility>

namespace saw::bench::can_bench {

using namespace std::chrono_literals;

SimProcess::SimProcess(const std::string& exe, std::vector<std::string> args, int cpu, std::string log)
    : log_(std::move(log)) {
  args.insert(args.begin(), exe);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  cpu_set_t set;
  CPU_ZERO(&set);
  if (cpu >= 0) CPU_SET(cpu, &set);
  pid_ = fork();
  if (pid_ == 0) {
    // Only async-signal-safe calls between fork and exec: this process has threads.
    (void)prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (cpu >= 0) (void)sched_setaffinity(0, sizeof set, &set);
    const int fd = open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd >= 0) {
      dup2(fd, STDOUT_FILENO);
      dup2(fd, STDERR_FILENO);
    }
    execv(argv[0], argv.data());
    _exit(127);
  }
  if (pid_ < 0) throw std::runtime_error("fork failed");
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while (text().find(" on virtual:") == std::string::npos) {
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      throw std::runtime_error("saw-can-sim exited: " + text());
    }
    if (std::chrono::steady_clock::now() > deadline) {
      stop();
      throw std::runtime_error("saw-can-sim did not say it was ready within 5 s: " + text());
    }
    std::this_thread::sleep_for(5ms);
  }
}

void SimProcess::stop() {
  if (pid_ <= 0) return;
  kill(pid_, SIGTERM);
  const auto deadline = std::chrono::steady_clock::now() + 2s;
  while (waitpid(pid_, nullptr, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
      break;
    }
    std::this_thread::sleep_for(2ms);
  }
  pid_ = -1;
}

std::string SimProcess::text() const {
  std::ifstream in(log_);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::uint64_t SimProcess::overruns() const {
  const std::string t = text();
  const auto at = t.find(" cycles, ");
  return at == std::string::npos ? 0 : std::strtoull(t.c_str() + at + 9, nullptr, 10);
}

}  // namespace saw::bench::can_bench

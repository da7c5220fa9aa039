// saw-can-sim, the drives, in a process of its own.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <string>
#include <vector>

namespace saw::bench::can_bench {

class SimProcess {
 public:
  // Starts `exe args...` (pinned to `cpu` unless -1) with stdout and stderr in `log`, and waits
  // for its line saying the drives are on the bus; throws std::runtime_error if it does not come.
  SimProcess(const std::string& exe, std::vector<std::string> args, int cpu, std::string log);
  ~SimProcess() { stop(); }
  SimProcess(const SimProcess&) = delete;
  SimProcess& operator=(const SimProcess&) = delete;

  // SIGTERM (it prints its summary), then reaped.
  void stop();
  std::string text() const;
  // From its summary ("saw-can-sim: 1.234 s, N cycles, M overruns ..."), after stop().
  std::uint64_t overruns() const;

 private:
  pid_t pid_ = -1;
  std::string log_;
};

}  // namespace saw::bench::can_bench

#include "saw/testing/child_process.hpp"

#include <signal.h>
#include <spawn.h>

extern char** environ;

namespace saw::testing {

ChildProcess::ChildProcess(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  if (argv.empty() || posix_spawn(&pid_, args[0], nullptr, nullptr, args.data(), environ) != 0) pid_ = -1;
}

ChildProcess::~ChildProcess() { kill9(); }

void ChildProcess::kill9() noexcept {
  if (pid_ <= 0) return;
  kill(pid_, SIGKILL);
  waitpid(pid_, nullptr, 0);
  pid_ = -1;
}

}  // namespace saw::testing

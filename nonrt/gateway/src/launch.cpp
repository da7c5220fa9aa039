// launch_gateway: saw-gateway as a process of its own beside the RT process, which never runs DDS.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <thread>

#include "saw/gateway/settings.hpp"

extern char** environ;

namespace saw::gateway {
namespace {

using namespace std::chrono_literals;

// An ordinary process, so that DDS never runs in the RT process.
struct GatewayProcess {
  pid_t pid = -1;
  ~GatewayProcess() {
    if (pid <= 0) return;
    kill(pid, SIGINT);  // an orderly stop; SIGTERM is what it gets when we die (no FAULT said here)
    waitpid(pid, nullptr, 0);
  }
};

std::string own_directory() {
  char self[4096] = {};
  const auto n = readlink("/proc/self/exe", self, sizeof self - 1);
  return n > 0 ? std::filesystem::path(std::string(self, static_cast<std::size_t>(n))).parent_path().string()
               : ".";
}

// The settings cross as one serialized form, read back by the same parser.
std::vector<std::string> arguments(const std::string& exe, const GatewaySettings& s) {
  // --wait: our own exports go live when the manager starts.
  return {exe, "--exit-with-parent", "--settings", to_yaml(s), "--wait", "30"};
}

bool presented(const std::string& name, const deploy::ComponentRegistry& registry) {
  for (const auto& make : registry.resolvers()) {
    try {
      if (make()->resolve(name) != nullptr) return true;
    } catch (const std::exception&) {  // there, not live yet
    }
  }
  return false;
}

}  // namespace

std::shared_ptr<void> launch_gateway(const GatewaySettings& spec, const deploy::ComponentRegistry& registry) {
  // Installed side by side (bin/ of the build, or the package's bin directory).
  const std::string exe = own_directory() + "/saw-gateway";
  if (access(exe.c_str(), X_OK) != 0)
    throw std::runtime_error("gateway: " + exe + " not found (build the nonrt/ targets)");
  for (const auto& i : spec.interfaces)
    if (spec.insecure && !i.starts_with("127.")) {
      std::fprintf(
          stderr,
          "saw-rt: warning: the gateway speaks DDS on %s without security (security: none): any host "
          "on that network can read and command these components\n",
          i.c_str());
      break;
    }
  auto args = arguments(exe, spec);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  auto p = std::make_shared<GatewayProcess>();
  if (const int err = posix_spawn(&p->pid, exe.c_str(), nullptr, nullptr, argv.data(), environ); err != 0)
    throw std::runtime_error("gateway: cannot start " + exe + ": " + std::strerror(err));
  // Mirrors of other hosts' components and imported arms: connect() will look for them here.
  std::vector<std::string> wanted;
  for (const auto& m : spec.mirrors) wanted.push_back(m.substr(m.find('=') + 1));  // NAME=LOCAL: LOCAL
  for (const auto& im : spec.imports) wanted.push_back(im.component);
  for (const auto& m : wanted) {
    const auto deadline = std::chrono::steady_clock::now() + 30s;
    while (!presented(m, registry)) {
      int status = 0;
      if (waitpid(p->pid, &status, WNOHANG) == p->pid) {
        p->pid = -1;
        throw std::runtime_error("gateway: exited before it could present '" + m + "' (see its output)");
      }
      if (std::chrono::steady_clock::now() > deadline)
        throw std::runtime_error("gateway: '" + m +
                                 "' was not presented here within 30 s (a mirror: is its host running?)");
      std::this_thread::sleep_for(50ms);
    }
  }
  return p;
}

}  // namespace saw::gateway

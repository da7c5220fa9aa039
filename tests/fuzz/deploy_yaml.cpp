// Fuzz target: the deployment parser on any text, with saw-rt's component types. Every problem
// must be a ConfigError naming the file (file:line:column: key '…': what); any other exception,
// or a crash, is a defect. Nothing leaves the process: exporting and the gateway are no-ops and
// no resolver looks for other processes' components.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "../deploy/packages.hpp"
#include "saw/deploy/deployment.hpp"
#include "saw/gateway/settings.hpp"

namespace {

// The types only: the bridge's resolver and exporter, a gateway and plug-ins reach outside.
saw::deploy::ComponentRegistry make_registry() {
  saw::deploy::ComponentRegistry r;
  saw::drivers::sim::register_components(r);
  saw::teleop::register_components(r);
  saw::gateway::register_components(r, false);  // the gateway: section, parsed; no process started
  r.set_exporter([](saw::Component&, const std::string&) { return std::shared_ptr<void>(); });
  r.allow_plugins(false);
  return r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static saw::deploy::ComponentRegistry registry = make_registry();
  const std::string text(reinterpret_cast<const char*>(data), size);
  // A file placed on hosts is parsed as one of them would (the seeds name this host).
  const std::string host = text.find("hosts") != std::string::npos ? "operator" : "";
  try {
    (void)saw::deploy::make_deployment(text, "fuzz.yaml", registry, host);
  } catch (const saw::deploy::ConfigError& e) {
    if (std::string_view(e.what()).substr(0, 10) != "fuzz.yaml:") {
      std::fprintf(stderr, "a ConfigError that does not name the file: %s\n", e.what());
      std::abort();
    }
  }
  return 0;
}

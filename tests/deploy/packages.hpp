// The in-tree packages' component types, registered as saw-rt registers them, for tests.
#pragma once

#include "saw/bridge/registration.hpp"
#include "saw/deploy/deployment.hpp"
#include "saw/drivers/sim_registration.hpp"
#include "saw/teleop/registration.hpp"

namespace saw::testing {

inline void register_packages(deploy::ComponentRegistry& r) {
  bridge::register_components(r);
  drivers::sim::register_components(r);
  teleop::register_components(r);
}

// One registry for a test binary (plug-ins a test loads stay loaded, as in saw-rt).
inline deploy::ComponentRegistry& registry() {
  static deploy::ComponentRegistry r = [] {
    deploy::ComponentRegistry x;
    register_packages(x);
    return x;
  }();
  return r;
}

// Parses and builds, as saw-rt does.
inline deploy::Deployment build(const std::string& text, const std::string& file,
                                deploy::ComponentRegistry& r, const std::string& host = "") {
  return deploy::make_deployment(text, file, r, host);
}

}  // namespace saw::testing

// Security CLI: `--enclave` for every DDS program, and sawctl's `security` subcommands.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "saw/gateway/participant.hpp"

namespace saw::gateway {

// --enclave DIR (a keystore's enclaves/NAME) into `dds.enclave`.
void add_enclave_option(CLI::App& app, ParticipantConfig& dds);

// One line to stdout: "DDS Security with enclave DIR (subject)", or that DDS runs without it.
void print_security(const ParticipantConfig& dds);

// `sawctl security init DIR [--sign-only]`, `security enroll DIR NAME --role R [--expires DAYS]
// [--component C]...`, `security revoke DIR NAME`, `security check ENCLAVE`: keystores need no DDS
// participant.
class SecurityCommands {
 public:
  explicit SecurityCommands(CLI::App& app);
  bool chosen() const { return security_->parsed(); }
  int run() const;  // prints what it made or why not; 0 on success

 private:
  CLI::App* security_;
  CLI::App *init_, *enroll_, *revoke_, *check_;
  std::string dir_, name_, role_;
  bool sign_only_ = false;
  int days_ = 365;
  std::vector<std::string> components_;
};

}  // namespace saw::gateway

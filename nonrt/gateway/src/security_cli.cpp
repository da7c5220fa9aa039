#include "security_cli.hpp"

#include <cstdio>
#include <ctime>

#include "saw/security/enclave.hpp"
#include "saw/security/keystore.hpp"

namespace saw::gateway {

namespace {

std::string utc_date(std::chrono::system_clock::time_point t) {
  const std::time_t tt = std::chrono::system_clock::to_time_t(t);
  std::tm tm{};
  gmtime_r(&tt, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M UTC", &tm);
  return buf;
}

}  // namespace

void add_enclave_option(CLI::App& app, ParticipantConfig& dds) {
  app.add_option_function<std::string>(
         "--enclave", [&dds](const std::string& dir) { dds.enclave = dir; },
         "DDS Security enclave KEYSTORE/enclaves/NAME (default: ROS_SECURITY_* environment, else none)")
      ->type_name("DIR");
}

void print_security(const ParticipantConfig& dds) {
  // Resolved again only to say it: the participant has already checked the same enclave.
  if (const auto dir = security::resolve_enclave(dds.enclave)) {
    const security::Enclave e = security::load_enclave(*dir);
    std::printf("  DDS Security with enclave %s (%s, valid until %s)\n", e.dir.c_str(), e.subject.c_str(),
                utc_date(e.not_after).c_str());
    if (!e.peers_start_handshake)
      std::printf(
          "  warning: this certificate was not enrolled with `sawctl security enroll --role gateway`: "
          "Cyclone DDS "
          "peers (sawgui, sawdds, ROS 2 on rmw_cyclonedds) whose subject hashes higher than %s, about half "
          "of "
          "them, cannot authenticate (Fast DDS 2.9 would start their handshake with a key encoding Cyclone "
          "DDS "
          "0.10 refuses; docs/security.md)\n",
          e.subject.c_str());
  } else {
    std::printf("  DDS without security (no enclave)\n");
  }
}

SecurityCommands::SecurityCommands(CLI::App& app) {
  security_ = app.add_subcommand("security", "DDS Security keystores: init, enroll, revoke, check");
  security_->require_subcommand(1);
  init_ = security_->add_subcommand("init", "create a keystore (identity and permissions CAs, governance)");
  init_->add_option("dir", dir_, "keystore directory")->required();
  init_->add_flag(
      "--sign-only", sign_only_,
      "authenticate every message but leave payloads unencrypted (a lab reading its own traffic)");
  enroll_ = security_->add_subcommand("enroll", "enrol an enclave: key, certificate, permissions for a role");
  enroll_->add_option("dir", dir_, "keystore directory")->required();
  enroll_->add_option("name", name_, "enclave name, e.g. gateway or lab/console")->required();
  enroll_->add_option("--role", role_, "monitor, operator or gateway")
      ->required()
      ->check(CLI::IsMember({"monitor", "operator", "gateway"}));
  enroll_->add_option("--expires", days_, "days until the certificate expires")->check(CLI::Range(1, 36500));
  enroll_->add_option("--component", components_,
                      "limit the grant to this component (repeatable; default all)");
  revoke_ = security_->add_subcommand(
      "revoke", "revoke an enclave's certificate: the keystore's crl.pem, linked into every enclave");
  revoke_->add_option("dir", dir_, "keystore directory")->required();
  revoke_->add_option("name", name_, "enclave name")->required();
  check_ =
      security_->add_subcommand("check", "check an enclave as saw-gateway and sawctl do before using it");
  check_->add_option("enclave", dir_, "KEYSTORE/enclaves/NAME")->required();
}

int SecurityCommands::run() const {
  try {
    if (init_->parsed()) {
      security::KeystoreOptions o;
      o.governance.sign_only = sign_only_;
      security::create_keystore(dir_, o);
      std::printf("keystore %s: identity and permissions CAs, governance (%s)\n", dir_.c_str(),
                  sign_only_ ? "sign-only: payloads authenticated, not encrypted" : "encrypted");
    } else if (enroll_->parsed()) {
      security::EnrollOptions o;
      o.role = security::parse_role(role_);
      o.days = days_;
      o.components = components_;
      const auto dir = security::enroll(dir_, name_, o);
      const security::Enclave e = security::load_enclave(dir);
      std::printf("enclave %s: %s, role %s, expires %s\n", dir.c_str(), e.subject.c_str(), role_.c_str(),
                  utc_date(e.not_after).c_str());
    } else if (revoke_->parsed()) {
      const std::string subject = security::revoke(dir_, name_);
      std::printf(
          "revoked %s: %s/public/crl.pem, linked as crl.pem into every enclave (copy it to hosts "
          "that hold copies of enclaves)\n",
          subject.c_str(), dir_.c_str());
    } else if (check_->parsed()) {
      const security::Enclave e = security::load_enclave(dir_);
      std::printf("enclave %s: %s, valid until %s\n", e.dir.c_str(), e.subject.c_str(),
                  utc_date(e.not_after).c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sawctl security: %s\n", e.what());
    return 1;
  }
}

}  // namespace saw::gateway

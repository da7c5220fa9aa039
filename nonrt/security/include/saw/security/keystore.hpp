// Keystore: a DDS Security keystore in SROS2's layout — CAs, governance, enrolled enclaves.
#pragma once

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "saw/security/policy.hpp"

namespace saw::security {

// DIR/public/{identity_ca,permissions_ca}.cert.pem, DIR/private/{identity_ca,permissions_ca}.key.pem,
// DIR/enclaves/governance.{xml,p7s}: what SROS2's `ros2 security create_keystore` makes and its
// other verbs expect, so `ros2 security create_enclave DIR /node` works on our keystores too.
struct KeystoreOptions {
  GovernanceOptions governance{};
  int ca_days = 3650;
  std::string common_name = "sawrt";  // CN prefix of the two CAs (then which CA and when it was made)
};

// Creates the keystore; throws std::runtime_error if DIR already holds one or cannot be written.
void create_keystore(const std::filesystem::path& dir, const KeystoreOptions& options = {});
// True when DIR has the CAs' certificates and keys and the signed governance.
bool is_keystore(const std::filesystem::path& dir);

struct EnrollOptions {
  Role role = Role::monitor;
  int days = 365;  // the certificate and its grant expire this many days from now
  std::optional<std::chrono::system_clock::time_point> not_after;  // instead of `days`
  // Start of the validity; a day before now by default, so a peer whose clock is a little
  // behind does not see the certificate as not yet valid.
  std::chrono::system_clock::time_point not_before =
      std::chrono::system_clock::now() - std::chrono::hours(24);
  std::vector<std::string> components;  // empty: every component
};

// Enrols enclave NAME (a path such as `gateway` or `lab/console`): DIR/enclaves/NAME/ gets
// key.pem and cert.pem (subject CN=/NAME, signed by the identity CA), the CAs' certificates and
// governance.p7s, and permissions.{xml,p7s} for the role. Enrolling an existing name again
// replaces its key, certificate and permissions. Returns the enclave's directory.
std::filesystem::path enroll(const std::filesystem::path& dir, const std::string& name,
                             const EnrollOptions& options);

// Revokes enclave NAME's certificate: DIR/public/crl.pem (signed by the identity CA, valid as long
// as the CA, earlier revocations kept) lists its serial, and every enclave of the keystore links
// it as crl.pem, where ROS 2 and sawrt's programs read it. Returns the enclave's subject.
std::string revoke(const std::filesystem::path& dir, const std::string& name);

}  // namespace saw::security

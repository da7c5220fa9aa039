// Enclave: one participant's security files, checked before DDS is given them.
#pragma once

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace saw::security {

struct Enclave {
  std::filesystem::path dir;
  std::filesystem::path identity_ca, certificate, private_key;    // authentication (PKI-DH)
  std::filesystem::path permissions_ca, governance, permissions;  // access control
  std::string subject;                                            // e.g. CN=/gateway
  std::chrono::system_clock::time_point not_after;
  // Domain ids (inclusive ranges) the governance protects and the permissions grant.
  std::vector<std::pair<int, int>> governance_domains, permission_domains;
  std::optional<std::filesystem::path> crl;  // crl.pem when the enclave has one (ROS 2 reads it too)
  // Whether a Fast DDS 2.9 participant with this certificate lets (practically) every Cyclone DDS
  // peer start the handshake, as `sawctl security enroll --role gateway` makes it. When false,
  // Cyclone DDS 0.10 peers whose subject hashes higher (about half) cannot authenticate with it.
  bool peers_start_handshake = false;
};

// Loads and checks DIR as an enclave at time `now`: every file present; the certificate valid
// now, issued by the enclave's identity CA and matching its key; governance and permissions
// signed by the permissions CA, the permissions granting the certificate's subject. Throws
// std::runtime_error "enclave DIR: <what is wrong>" — DDS's own errors do not say which.
Enclave load_enclave(const std::filesystem::path& dir,
                     std::chrono::system_clock::time_point now = std::chrono::system_clock::now());

// Throws std::runtime_error "enclave DIR: domain D is not in the governance's domains 0-5" (or
// the permissions') when a participant of this enclave could not use `domain`.
void check_domain(const Enclave& enclave, int domain);

// The enclave a participant must use: `explicit_dir` when given, else the one the ROS 2
// environment names (ROS_SECURITY_ENABLE=true, ROS_SECURITY_KEYSTORE,
// ROS_SECURITY_ENCLAVE_OVERRIDE), else none. With security enabled a missing enclave is an
// error whatever ROS_SECURITY_STRATEGY says: sawrt never falls back to plaintext.
std::optional<std::filesystem::path> resolve_enclave(
    const std::optional<std::filesystem::path>& explicit_dir);

}  // namespace saw::security

#include "participant_security.hpp"

#include "saw/security/enclave.hpp"

namespace saw::gateway {

namespace {

std::string file_uri(const std::filesystem::path& p) { return "file://" + p.string(); }

}  // namespace

std::string apply_security(eprosima::fastdds::dds::DomainParticipantQos& qos,
                           const ParticipantConfig& config) {
  const auto dir = security::resolve_enclave(config.enclave);
  if (!dir) return "";
  // Checked here first: Fast DDS says only that validation failed, not which file or why.
  const security::Enclave e = security::load_enclave(*dir);
  security::check_domain(e, config.domain);
  auto& props = qos.properties().properties();
  auto set = [&](const std::string& name, const std::string& value) { props.emplace_back(name, value); };
  set("dds.sec.auth.plugin", "builtin.PKI-DH");
  set("dds.sec.auth.builtin.PKI-DH.identity_ca", file_uri(e.identity_ca));
  set("dds.sec.auth.builtin.PKI-DH.identity_certificate", file_uri(e.certificate));
  set("dds.sec.auth.builtin.PKI-DH.private_key", file_uri(e.private_key));
  // The enclave's revocation list, as ROS 2 passes it: a revoked peer is not authenticated.
  if (e.crl) set("dds.sec.auth.builtin.PKI-DH.identity_crl", file_uri(*e.crl));
  set("dds.sec.access.plugin", "builtin.Access-Permissions");
  set("dds.sec.access.builtin.Access-Permissions.permissions_ca", file_uri(e.permissions_ca));
  set("dds.sec.access.builtin.Access-Permissions.governance", file_uri(e.governance));
  set("dds.sec.access.builtin.Access-Permissions.permissions", file_uri(e.permissions));
  set("dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC");
  return e.dir.string();
}

}  // namespace saw::gateway

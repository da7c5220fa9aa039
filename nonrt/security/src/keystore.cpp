#include "saw/security/keystore.hpp"

#include <cctype>
#include <ctime>
#include <fstream>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "handshake_order.hpp"
#include "openssl.hpp"

namespace saw::security {

namespace fs = std::filesystem;

namespace {

using std::chrono::system_clock;

void write_file(const fs::path& file, const std::string& text, bool secret) {
  if (secret) {
    // Created empty and private before the key goes in, so it is never readable by others.
    std::ofstream(file, std::ios::trunc).close();
    fs::permissions(file, fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace);
  }
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  if (!out) throw std::runtime_error(file.string() + ": cannot write");
}

// A relative symbolic link, as SROS2 makes them: the keystore can be moved or copied whole.
void link_to(const fs::path& target, const fs::path& link) {
  std::error_code ec;
  fs::remove(link, ec);
  fs::create_symlink(fs::relative(target, link.parent_path()), link);
}

// Named with their creation time, so that two keystores' CAs are told apart in errors.
void make_ca(const fs::path& dir, const std::string& which, const KeystoreOptions& o,
             system_clock::time_point now) {
  const std::time_t t = system_clock::to_time_t(now);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char created[32];
  std::strftime(created, sizeof created, "%Y-%m-%dT%H:%M:%SZ", &tm);
  ossl::Key key = ossl::generate_p256();
  ossl::Cert cert =
      ossl::make_certificate({o.common_name + " " + which + " CA " + created, now - std::chrono::hours(24),
                              now + std::chrono::days(o.ca_days), true},
                             key.get(), nullptr, key.get());
  write_file(dir / "private" / (which + "_ca.key.pem"), ossl::pem_pkcs8(key.get()), true);
  write_file(dir / "public" / (which + "_ca.cert.pem"), ossl::pem(cert.get()), false);
}

// NAME as a relative path of segments of letters, digits and '_' (ROS 2's rule for enclaves).
fs::path enclave_path(const std::string& name) {
  std::string n = name;
  while (!n.empty() && n.front() == '/') n.erase(0, 1);
  if (n.empty()) throw std::invalid_argument("enclave name '" + name + "' is empty");
  std::size_t start = 0;
  for (;;) {
    const std::size_t end = n.find('/', start);
    const std::string seg = n.substr(start, end == std::string::npos ? std::string::npos : end - start);
    bool ok = !seg.empty() && !std::isdigit(static_cast<unsigned char>(seg.front()));
    for (char c : seg) ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_');
    if (!ok)
      throw std::invalid_argument("enclave name '" + name +
                                  "': segments of letters, digits and '_', not starting with a digit, "
                                  "separated by '/'");
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return fs::path(n);
}

}  // namespace

bool is_keystore(const fs::path& dir) {
  return fs::is_regular_file(dir / "public" / "identity_ca.cert.pem") &&
         fs::is_regular_file(dir / "public" / "permissions_ca.cert.pem") &&
         fs::is_regular_file(dir / "private" / "identity_ca.key.pem") &&
         fs::is_regular_file(dir / "private" / "permissions_ca.key.pem") &&
         fs::is_regular_file(dir / "enclaves" / "governance.p7s");
}

void create_keystore(const fs::path& dir, const KeystoreOptions& o) {
  if (is_keystore(dir)) throw std::runtime_error("keystore " + dir.string() + ": already exists");
  if (o.ca_days < 1) throw std::invalid_argument("CA validity: at least one day");
  if (o.governance.domain_min < 0 || o.governance.domain_max > 230 ||
      o.governance.domain_min > o.governance.domain_max)
    throw std::invalid_argument("governance domains: a range within 0-230");
  fs::create_directories(dir / "public");
  fs::create_directories(dir / "private");
  fs::create_directories(dir / "enclaves");
  fs::permissions(dir / "private", fs::perms::owner_all, fs::perm_options::replace);
  const auto now = system_clock::now();
  make_ca(dir, "identity", o, now);
  make_ca(dir, "permissions", o, now);
  const std::string governance = governance_xml(o.governance);
  write_file(dir / "enclaves" / "governance.xml", governance, false);
  ossl::Cert ca = ossl::read_cert(dir / "public" / "permissions_ca.cert.pem");
  ossl::Key ca_key = ossl::read_key(dir / "private" / "permissions_ca.key.pem");
  write_file(dir / "enclaves" / "governance.p7s", ossl::smime_sign(governance, ca.get(), ca_key.get()),
             false);
}

namespace {

// Every file of an enclave, written into `into` (a fresh directory beside the final one, so the
// relative links are the same).
void write_enclave(const fs::path& dir, const fs::path& rel, const fs::path& into, const EnrollOptions& o) {
  ossl::Cert id_ca = ossl::read_cert(dir / "public" / "identity_ca.cert.pem");
  ossl::Key id_key = ossl::read_key(dir / "private" / "identity_ca.key.pem");
  ossl::Key key = ossl::generate_p256();
  const auto not_after = o.not_after.value_or(system_clock::now() + std::chrono::days(o.days));
  if (not_after <= o.not_before)
    throw std::invalid_argument("enrol " + rel.generic_string() + ": the validity ends before it starts");
  const std::string subject_cn = "/" + rel.generic_string();
  // A gateway is a Fast DDS server: its subject is chosen so that Cyclone DDS peers start the
  // handshake (handshake_order.hpp).
  const std::string serial = o.role == Role::gateway ? ossl::high_order_serial(subject_cn) : std::string();
  ossl::Cert cert = ossl::make_certificate({subject_cn, o.not_before, not_after, false, serial}, key.get(),
                                           id_ca.get(), id_key.get());
  write_file(into / "key.pem", ossl::pem_pkcs8(key.get()), true);
  write_file(into / "cert.pem", ossl::pem(cert.get()), false);
  link_to(dir / "public" / "identity_ca.cert.pem", into / "identity_ca.cert.pem");
  link_to(dir / "public" / "permissions_ca.cert.pem", into / "permissions_ca.cert.pem");
  link_to(dir / "enclaves" / "governance.p7s", into / "governance.p7s");

  Grant grant;
  grant.subject = ossl::subject(cert.get());
  grant.role = o.role;
  grant.not_before = ossl::not_before(cert.get());
  grant.not_after = ossl::not_after(cert.get());
  grant.components = o.components;
  const std::string permissions = permissions_xml(grant);
  write_file(into / "permissions.xml", permissions, false);
  ossl::Cert p_ca = ossl::read_cert(dir / "public" / "permissions_ca.cert.pem");
  ossl::Key p_key = ossl::read_key(dir / "private" / "permissions_ca.key.pem");
  write_file(into / "permissions.p7s", ossl::smime_sign(permissions, p_ca.get(), p_key.get()), false);
  if (fs::exists(dir / "public" / "crl.pem")) link_to(dir / "public" / "crl.pem", into / "crl.pem");
}

// The folders of `path` that do not exist yet, outermost first.
std::vector<fs::path> missing_folders(const fs::path& path) {
  std::vector<fs::path> out;
  for (fs::path p = path; !p.empty() && !fs::exists(p); p = p.parent_path()) out.insert(out.begin(), p);
  return out;
}

}  // namespace

fs::path enroll(const fs::path& dir, const std::string& name, const EnrollOptions& o) {
  if (!is_keystore(dir))
    throw std::runtime_error(
        "keystore " + dir.string() +
        ": not a keystore (no CAs or governance; create it with `sawctl security init`)");
  if (o.days < 1) throw std::invalid_argument("--expires: at least one day");
  const fs::path rel = enclave_path(name);
  const fs::path enclave = dir / "enclaves" / rel;
  if (rel == "governance.xml" || rel == "governance.p7s")
    throw std::invalid_argument("enclave name '" + name + "' is a keystore file's name");
  // Made in a staging folder beside its place, then renamed into it: a failed enrolment leaves
  // nothing behind (not even the parent folders of lab/console) and an enclave being replaced
  // keeps its old files until the new ones are all made. A replaced enclave's files are renamed
  // over one by one, as it may hold other enclaves' folders (lab and lab/console).
  const std::vector<fs::path> created = missing_folders(enclave.parent_path());
  const fs::path staging = enclave.parent_path() / ("." + enclave.filename().string() + ".enrolling");
  try {
    fs::create_directories(enclave.parent_path());
    fs::remove_all(staging);
    fs::create_directory(staging);
    write_enclave(dir, rel, staging, o);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(staging, ec);
    for (auto it = created.rbegin(); it != created.rend(); ++it) fs::remove(*it, ec);  // only if empty
    throw;
  }
  if (!fs::exists(enclave)) {
    fs::rename(staging, enclave);
  } else {
    for (const auto& f : fs::directory_iterator(staging)) fs::rename(f.path(), enclave / f.path().filename());
    fs::remove(staging);
  }
  return enclave;
}

std::string revoke(const fs::path& dir, const std::string& name) {
  if (!is_keystore(dir))
    throw std::runtime_error("keystore " + dir.string() + ": not a keystore (no CAs or governance)");
  const fs::path enclave = dir / "enclaves" / enclave_path(name);
  if (!fs::is_regular_file(enclave / "cert.pem"))
    throw std::runtime_error("enclave " + enclave.string() + ": no cert.pem to revoke");
  ossl::Cert cert = ossl::read_cert(enclave / "cert.pem");
  ossl::Cert ca = ossl::read_cert(dir / "public" / "identity_ca.cert.pem");
  ossl::Key ca_key = ossl::read_key(dir / "private" / "identity_ca.key.pem");
  if (!ossl::verify_issued_by(cert.get(), ca.get()).empty())
    throw std::runtime_error("enclave " + enclave.string() +
                             ": its certificate is not this keystore's identity CA's");
  const fs::path crl_file = dir / "public" / "crl.pem";
  std::vector<std::pair<std::string, system_clock::time_point>> entries;
  if (fs::exists(crl_file)) {
    ossl::Crl old = ossl::read_crl(crl_file);
    if (!ossl::crl_signed_by(old.get(), ca.get()))
      throw std::runtime_error(crl_file.string() + ": not issued by this keystore's identity CA");
    entries = ossl::revoked(old.get());
  }
  const std::string serial = ossl::serial_hex(cert.get());
  bool listed = false;
  for (const auto& e : entries) listed = listed || e.first == serial;
  if (!listed) entries.emplace_back(serial, system_clock::now());
  // Valid as long as the CA: an expired CRL makes DDS Security refuse every peer.
  ossl::Crl crl = ossl::make_crl(ca.get(), ca_key.get(), entries, ossl::not_after(ca.get()));
  const fs::path staging = dir / "public" / ".crl.pem.new";
  write_file(staging, ossl::pem(crl.get()), false);
  fs::rename(staging, crl_file);
  for (const auto& entry : fs::recursive_directory_iterator(dir / "enclaves"))
    if (entry.is_regular_file() && entry.path().filename() == "cert.pem")
      link_to(crl_file, entry.path().parent_path() / "crl.pem");
  return ossl::subject(cert.get());
}

}  // namespace saw::security

#include "saw/security/enclave.hpp"

#include <cstdlib>
#include <ctime>
#include <fstream>
#include <stdexcept>

#include "openssl.hpp"

namespace saw::security {

namespace fs = std::filesystem;
using std::chrono::system_clock;

namespace {

std::string utc(system_clock::time_point t) {
  const std::time_t tt = system_clock::to_time_t(t);
  std::tm tm{};
  gmtime_r(&tt, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M:%S UTC", &tm);
  return buf;
}

std::string read_file(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(file.filename().string() + ": cannot read");
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Subjects compared as DDS Security does (RFC 2253), ignoring spaces around separators.
std::string squeezed(const std::string& s) {
  std::string out;
  for (char c : s)
    if (c != ' ' && c != '\t' && c != '\n' && c != '\r') out += c;
  return out;
}

bool grants_subject(const std::string& permissions, const std::string& subject) {
  const std::string open = "<subject_name>", close = "</subject_name>";
  for (std::size_t at = permissions.find(open); at != std::string::npos;
       at = permissions.find(open, at + 1)) {
    const std::size_t from = at + open.size(), to = permissions.find(close, from);
    if (to == std::string::npos) break;
    if (squeezed(permissions.substr(from, to - from)) == squeezed(subject)) return true;
  }
  return false;
}

void check_certificate(Enclave& e, system_clock::time_point now) {
  ossl::Cert ca = ossl::read_cert(e.identity_ca);
  ossl::Cert cert = ossl::read_cert(e.certificate);
  e.subject = ossl::subject(cert.get());
  e.not_after = ossl::not_after(cert.get());
  if (now > e.not_after)
    throw std::runtime_error("certificate " + e.subject + " expired on " + utc(e.not_after));
  if (now < ossl::not_before(cert.get()))
    throw std::runtime_error("certificate " + e.subject + " is not valid before " +
                             utc(ossl::not_before(cert.get())));
  if (now > ossl::not_after(ca.get()))
    throw std::runtime_error("identity CA " + ossl::subject(ca.get()) + " expired on " +
                             utc(ossl::not_after(ca.get())));
  if (const std::string why = ossl::verify_issued_by(cert.get(), ca.get()); !why.empty())
    throw std::runtime_error("certificate " + e.subject + " (issued by " + ossl::issuer(cert.get()) +
                             ") is not accepted by the enclave's identity CA " + ossl::subject(ca.get()) +
                             ": " + why + " (enrolled from another keystore?)");
  ossl::Key key = ossl::read_key(e.private_key);
  if (X509_check_private_key(cert.get(), key.get()) != 1)
    throw std::runtime_error(ossl::last_error("key.pem is not the key of cert.pem"));
}

void check_signed(const fs::path& file, X509* ca, const std::string& subject_to_grant) {
  std::string text;
  try {
    text = ossl::smime_verify(read_file(file), ca);
  } catch (const std::exception& ex) {
    throw std::runtime_error(file.filename().string() + " is not signed by the enclave's permissions CA " +
                             ossl::subject(ca) + ": " + ex.what());
  }
  if (!subject_to_grant.empty() && !grants_subject(text, subject_to_grant))
    throw std::runtime_error(file.filename().string() + " has no grant for " + subject_to_grant);
}

}  // namespace

Enclave load_enclave(const fs::path& dir, system_clock::time_point now) {
  Enclave e;
  e.dir = fs::absolute(dir).lexically_normal();
  e.identity_ca = e.dir / "identity_ca.cert.pem";
  e.certificate = e.dir / "cert.pem";
  e.private_key = e.dir / "key.pem";
  e.permissions_ca = e.dir / "permissions_ca.cert.pem";
  e.governance = e.dir / "governance.p7s";
  e.permissions = e.dir / "permissions.p7s";
  try {
    if (!fs::is_directory(e.dir)) throw std::runtime_error("no such directory");
    for (const auto& f :
         {e.identity_ca, e.certificate, e.private_key, e.permissions_ca, e.governance, e.permissions})
      if (!fs::is_regular_file(f)) throw std::runtime_error("missing " + f.filename().string());
    check_certificate(e, now);
    ossl::Cert permissions_ca = ossl::read_cert(e.permissions_ca);
    check_signed(e.governance, permissions_ca.get(), "");
    check_signed(e.permissions, permissions_ca.get(), e.subject);
  } catch (const std::exception& ex) {
    throw std::runtime_error("enclave " + dir.string() + ": " + ex.what());
  }
  return e;
}

std::optional<fs::path> resolve_enclave(const std::optional<fs::path>& explicit_dir) {
  if (explicit_dir) return explicit_dir;
  auto env = [](const char* name) -> std::string {
    const char* v = std::getenv(name);
    return v == nullptr ? "" : v;
  };
  if (env("ROS_SECURITY_ENABLE") != "true") return std::nullopt;
  const std::string keystore = env("ROS_SECURITY_KEYSTORE"), enclave = env("ROS_SECURITY_ENCLAVE_OVERRIDE");
  if (keystore.empty())
    throw std::runtime_error(
        "ROS_SECURITY_ENABLE=true but ROS_SECURITY_KEYSTORE is not set (no plaintext fallback)");
  if (enclave.empty())
    throw std::runtime_error(
        "ROS_SECURITY_ENABLE=true but ROS_SECURITY_ENCLAVE_OVERRIDE is not set: name this program's enclave "
        "(e.g. /gateway) or pass --enclave (no plaintext fallback)");
  const fs::path dir = fs::path(keystore) / "enclaves" / fs::path(enclave).relative_path();
  if (!fs::is_directory(dir))
    throw std::runtime_error("enclave " + dir.string() + " (from ROS_SECURITY_KEYSTORE and " +
                             "ROS_SECURITY_ENCLAVE_OVERRIDE) does not exist; sawrt does not fall back to " +
                             "plaintext whatever ROS_SECURITY_STRATEGY says");
  return dir;
}

}  // namespace saw::security

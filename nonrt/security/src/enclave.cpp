#include "saw/security/enclave.hpp"

#include <cstdlib>
#include <ctime>
#include <fstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "handshake_order.hpp"
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
  e.peers_start_handshake = ossl::order_bits(cert.get()) >= ossl::kOrderBits;
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

std::string between(const std::string& s, std::size_t& at, const std::string& open, const std::string& close,
                    std::size_t limit) {
  const std::size_t from = s.find(open, at);
  if (from == std::string::npos || from >= limit) return "";
  const std::size_t to = s.find(close, from + open.size());
  if (to == std::string::npos || to > limit) return "";
  at = to + close.size();
  return s.substr(from + open.size(), to - from - open.size());
}

int number(const std::string& s, int fallback) {
  try {
    return s.empty() ? fallback : std::stoi(s);
  } catch (const std::exception&) {
    return fallback;
  }
}

// Every <domains> of a governance or permissions document: <id>N</id> and <id_range> (min and
// max, either optional).
std::vector<std::pair<int, int>> domains_of(const std::string& xml) {
  std::vector<std::pair<int, int>> out;
  std::size_t at = 0;
  for (std::size_t open = xml.find("<domains>", at); open != std::string::npos;
       open = xml.find("<domains>", at)) {
    const std::size_t close = xml.find("</domains>", open);
    if (close == std::string::npos) break;
    for (std::size_t p = open; p < close;) {
      const std::size_t id = xml.find("<id>", p), range = xml.find("<id_range>", p);
      if (id < close && id < range) {
        std::size_t q = id;
        const int n = number(between(xml, q, "<id>", "</id>", close), -1);
        out.emplace_back(n, n);
        p = q;
      } else if (range < close) {
        std::size_t q = range;
        const std::string body = between(xml, q, "<id_range>", "</id_range>", close);
        std::size_t b = 0;
        const int lo = number(between(body, b, "<min>", "</min>", body.size()), 0);
        b = 0;
        const int hi = number(between(body, b, "<max>", "</max>", body.size()), 232);
        out.emplace_back(lo, hi);
        p = q;
      } else {
        break;
      }
    }
    at = close + 1;
  }
  return out;
}

std::string ranges_text(const std::vector<std::pair<int, int>>& ranges) {
  std::string out;
  for (const auto& [lo, hi] : ranges)
    out += (out.empty() ? "" : ", ") +
           (lo == hi ? std::to_string(lo) : std::to_string(lo) + "-" + std::to_string(hi));
  return out.empty() ? "(none)" : out;
}

bool in(const std::vector<std::pair<int, int>>& ranges, int d) {
  for (const auto& [lo, hi] : ranges)
    if (d >= lo && d <= hi) return true;
  return false;
}

// crl.pem, when the enclave has one: issued by the identity CA, current, and not revoking the
// enclave's own certificate. Fast DDS would otherwise refuse every peer (an expired CRL) or
// start a participant no peer accepts.
void check_crl(const Enclave& e, system_clock::time_point now) {
  ossl::Crl crl = ossl::read_crl(*e.crl);
  ossl::Cert ca = ossl::read_cert(e.identity_ca);
  if (!ossl::crl_signed_by(crl.get(), ca.get()))
    throw std::runtime_error("crl.pem is not issued by the enclave's identity CA " + ossl::subject(ca.get()));
  const auto next = ossl::next_update(crl.get());
  if (next != system_clock::time_point{} && now > next)
    throw std::runtime_error(
        "crl.pem expired on " + utc(next) +
        " (DDS Security would refuse every peer): issue it again with `sawctl security revoke`");
  ossl::Cert cert = ossl::read_cert(e.certificate);
  const std::string serial = ossl::serial_hex(cert.get());
  for (const auto& [s, when] : ossl::revoked(crl.get()))
    if (s == serial)
      throw std::runtime_error("certificate " + e.subject + " was revoked on " + utc(when) + " (crl.pem)");
}

std::string check_signed(const fs::path& file, X509* ca, const std::string& subject_to_grant) {
  std::string text;
  try {
    text = ossl::smime_verify(read_file(file), ca);
  } catch (const std::exception& ex) {
    throw std::runtime_error(file.filename().string() + " is not signed by the enclave's permissions CA " +
                             ossl::subject(ca) + ": " + ex.what());
  }
  if (!subject_to_grant.empty() && !grants_subject(text, subject_to_grant))
    throw std::runtime_error(file.filename().string() + " has no grant for " + subject_to_grant);
  return text;
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
    e.governance_domains = domains_of(check_signed(e.governance, permissions_ca.get(), ""));
    e.permission_domains = domains_of(check_signed(e.permissions, permissions_ca.get(), e.subject));
    if (fs::exists(e.dir / "crl.pem")) {
      e.crl = e.dir / "crl.pem";
      check_crl(e, now);
    }
  } catch (const std::exception& ex) {
    throw std::runtime_error("enclave " + dir.string() + ": " + ex.what());
  }
  return e;
}

void check_domain(const Enclave& e, int domain) {
  if (!in(e.governance_domains, domain))
    throw std::runtime_error("enclave " + e.dir.string() + ": domain " + std::to_string(domain) +
                             " is not in the governance's domains " + ranges_text(e.governance_domains) +
                             " (governance.p7s): DDS Security would refuse every topic there");
  if (!in(e.permission_domains, domain))
    throw std::runtime_error("enclave " + e.dir.string() + ": domain " + std::to_string(domain) +
                             " is not in the permissions' domains " + ranges_text(e.permission_domains) +
                             " (permissions.p7s of " + e.subject + ")");
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

// OpenSSL: the few libcrypto operations a keystore needs, as owning C++ values that throw.
#pragma once

#include <openssl/evp.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace saw::security::ossl {

struct FreeKey {
  void operator()(EVP_PKEY* p) const noexcept { EVP_PKEY_free(p); }
};
struct FreeCert {
  void operator()(X509* p) const noexcept { X509_free(p); }
};
struct FreeCrl {
  void operator()(X509_CRL* p) const noexcept { X509_CRL_free(p); }
};
using Key = std::unique_ptr<EVP_PKEY, FreeKey>;
using Cert = std::unique_ptr<X509, FreeCert>;
using Crl = std::unique_ptr<X509_CRL, FreeCrl>;
using TimePoint = std::chrono::system_clock::time_point;

// What OpenSSL's error queue says (emptying it), or `fallback` when it says nothing.
std::string last_error(const std::string& fallback);

// A new ECDSA key on prime256v1, the curve DDS Security's builtin plugins require.
Key generate_p256();

struct CertRequest {
  std::string common_name;
  TimePoint not_before;
  TimePoint not_after;
  bool ca = false;
  // A subject serialNumber attribute after the CN (none when empty): see handshake_order.hpp.
  std::string subject_serial{};
};
// CN=common_name, then serialNumber=serial unless empty: the subject make_certificate writes.
void add_subject_entries(X509_NAME* name, const std::string& common_name, const std::string& serial);
// An X.509 v3 certificate for `subject_key`, signed with SHA-256 by `issuer_key`; self-signed
// when `issuer` is null.
Cert make_certificate(const CertRequest& request, EVP_PKEY* subject_key, X509* issuer, EVP_PKEY* issuer_key);

std::string pem(X509* cert);
std::string pem_pkcs8(EVP_PKEY* key);  // unencrypted, as SROS2 writes it
Cert read_cert(const std::filesystem::path& file);
Key read_key(const std::filesystem::path& file);

// `text` signed as S/MIME (clear-signed, detached, text/plain): what `openssl smime -sign -text`
// writes and what DDS Security's Access-Permissions plugin verifies.
std::string smime_sign(const std::string& text, X509* cert, EVP_PKEY* key);
// The signed text of an S/MIME document when `ca` verifies its signature; throws with OpenSSL's
// reason otherwise.
std::string smime_verify(const std::string& document, X509* ca);

TimePoint not_before(X509* cert);
TimePoint not_after(X509* cert);
std::string subject(X509* cert);  // RFC 2253, e.g. CN=/gateway
std::string issuer(X509* cert);
// Certificate revocation lists (RFC 5280 v2), as `openssl ca -gencrl` writes them.
Crl read_crl(const std::filesystem::path& file);
std::string pem(X509_CRL* crl);
// A CRL issued by `ca` listing `revoked` (serial and revocation time) with the given next update.
Crl make_crl(X509* ca, EVP_PKEY* ca_key, const std::vector<std::pair<std::string, TimePoint>>& revoked,
             TimePoint next_update);
// Its entries: serial (hex) and revocation time.
std::vector<std::pair<std::string, TimePoint>> revoked(X509_CRL* crl);
bool crl_signed_by(X509_CRL* crl, X509* ca);
TimePoint next_update(X509_CRL* crl);  // or the epoch when it has none
std::string serial_hex(X509* cert);

// Why `cert` does not chain to `ca` (OpenSSL's verification, dates included), or "" if it does.
std::string verify_issued_by(X509* cert, X509* ca);

}  // namespace saw::security::ossl

// OpenSSL: the few libcrypto operations a keystore needs, as owning C++ values that throw.
#pragma once

#include <openssl/evp.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>

namespace saw::security::ossl {

struct FreeKey {
  void operator()(EVP_PKEY* p) const noexcept { EVP_PKEY_free(p); }
};
struct FreeCert {
  void operator()(X509* p) const noexcept { X509_free(p); }
};
using Key = std::unique_ptr<EVP_PKEY, FreeKey>;
using Cert = std::unique_ptr<X509, FreeCert>;
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
};
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
// Why `cert` does not chain to `ca` (OpenSSL's verification, dates included), or "" if it does.
std::string verify_issued_by(X509* cert, X509* ca);

}  // namespace saw::security::ossl

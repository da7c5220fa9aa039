#include "openssl.hpp"

#include <openssl/asn1.h>
#include <openssl/bio.h>
#include <openssl/bn.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/x509v3.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace saw::security::ossl {

namespace {

struct FreeBio {
  void operator()(BIO* p) const noexcept { BIO_free(p); }
};
struct FreePkcs7 {
  void operator()(PKCS7* p) const noexcept { PKCS7_free(p); }
};
struct FreeStore {
  void operator()(X509_STORE* p) const noexcept { X509_STORE_free(p); }
};
struct FreeStoreCtx {
  void operator()(X509_STORE_CTX* p) const noexcept { X509_STORE_CTX_free(p); }
};
struct FreeAsn1Time {
  void operator()(ASN1_TIME* p) const noexcept { ASN1_TIME_free(p); }
};
using Bio = std::unique_ptr<BIO, FreeBio>;

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(last_error(what)); }

template <class T>
T* check(T* p, const char* what) {
  if (p == nullptr) fail(what);
  return p;
}
void check(int ok, const char* what) {
  if (ok != 1) fail(what);
}

Bio memory_bio() { return Bio(check(BIO_new(BIO_s_mem()), "BIO_new")); }
// Reads `s` in place: `s` must outlive the BIO.
Bio memory_bio(const std::string& s) {
  return Bio(check(BIO_new_mem_buf(s.data(), static_cast<int>(s.size())), "BIO_new_mem_buf"));
}
std::string text_of(BIO* b) {
  char* data = nullptr;
  const long n = BIO_get_mem_data(b, &data);
  return n > 0 ? std::string(data, static_cast<std::size_t>(n)) : std::string();
}

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(file.string() + ": cannot read");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TimePoint time_of(const ASN1_TIME* t) {
  struct tm tm {};
  if (ASN1_TIME_to_tm(t, &tm) != 1) fail("ASN1_TIME_to_tm");
  return std::chrono::system_clock::from_time_t(timegm(&tm));
}

void set_time(X509* cert, TimePoint t, bool before) {
  std::unique_ptr<ASN1_TIME, FreeAsn1Time> a(
      check(ASN1_TIME_set(nullptr, std::chrono::system_clock::to_time_t(t)), "ASN1_TIME_set"));
  check(before ? X509_set1_notBefore(cert, a.get()) : X509_set1_notAfter(cert, a.get()), "X509 validity");
}

void add_extension(X509* cert, X509* issuer, int nid, const char* value) {
  X509V3_CTX ctx;
  X509V3_set_ctx(&ctx, issuer, cert, nullptr, nullptr, 0);
  X509_EXTENSION* ext = check(X509V3_EXT_conf_nid(nullptr, &ctx, nid, value), "X509V3_EXT_conf_nid");
  const int ok = X509_add_ext(cert, ext, -1);
  X509_EXTENSION_free(ext);
  check(ok, "X509_add_ext");
}

std::string name_text(const X509_NAME* name) {
  Bio b = memory_bio();
  X509_NAME_print_ex(b.get(), name, 0, XN_FLAG_RFC2253);
  return text_of(b.get());
}

}  // namespace

std::string last_error(const std::string& fallback) {
  std::string out;
  for (unsigned long e = ERR_get_error(); e != 0; e = ERR_get_error()) {
    char buf[256];
    ERR_error_string_n(e, buf, sizeof buf);
    out += (out.empty() ? "" : "; ") + std::string(buf);
  }
  return out.empty() ? fallback : fallback + ": " + out;
}

Key generate_p256() { return Key(check(EVP_EC_gen("P-256"), "generating a P-256 key")); }

void add_subject_entries(X509_NAME* name, const std::string& common_name, const std::string& serial) {
  check(X509_NAME_add_entry_by_txt(name, "CN", MBSTRING_UTF8,
                                   reinterpret_cast<const unsigned char*>(common_name.c_str()), -1, -1, 0),
        "subject name");
  if (!serial.empty())
    check(X509_NAME_add_entry_by_txt(name, "serialNumber", MBSTRING_ASC,
                                     reinterpret_cast<const unsigned char*>(serial.c_str()), -1, -1, 0),
          "subject serialNumber");
}

Cert make_certificate(const CertRequest& r, EVP_PKEY* subject_key, X509* issuer, EVP_PKEY* issuer_key) {
  Cert cert(check(X509_new(), "X509_new"));
  check(X509_set_version(cert.get(), X509_VERSION_3), "X509_set_version");
  // A random 159-bit serial (positive, at most 20 octets, as RFC 5280 asks).
  std::unique_ptr<BIGNUM, decltype(&BN_free)> serial(check(BN_new(), "BN_new"), BN_free);
  check(BN_rand(serial.get(), 159, BN_RAND_TOP_ANY, BN_RAND_BOTTOM_ANY), "BN_rand");
  check(BN_to_ASN1_INTEGER(serial.get(), X509_get_serialNumber(cert.get())) != nullptr ? 1 : 0,
        "BN_to_ASN1_INTEGER");
  set_time(cert.get(), r.not_before, true);
  set_time(cert.get(), r.not_after, false);
  X509_NAME* name = X509_get_subject_name(cert.get());
  add_subject_entries(name, r.common_name, r.subject_serial);
  check(X509_set_issuer_name(cert.get(), issuer != nullptr ? X509_get_subject_name(issuer) : name),
        "issuer name");
  check(X509_set_pubkey(cert.get(), subject_key), "X509_set_pubkey");
  X509* signer = issuer != nullptr ? issuer : cert.get();
  add_extension(cert.get(), signer, NID_basic_constraints, r.ca ? "critical,CA:TRUE,pathlen:1" : "CA:FALSE");
  add_extension(cert.get(), signer, NID_subject_key_identifier, "hash");
  // The issuer's key identifier when it has one; else its name and serial. SROS2's CA has no
  // subject key identifier, and "keyid:always" would refuse to enrol into its keystore.
  add_extension(cert.get(), signer, NID_authority_key_identifier, "keyid,issuer");
  if (X509_sign(cert.get(), issuer_key, EVP_sha256()) <= 0) fail("X509_sign");
  return cert;
}

std::string pem(X509* cert) {
  Bio b = memory_bio();
  check(PEM_write_bio_X509(b.get(), cert), "PEM_write_bio_X509");
  return text_of(b.get());
}

std::string pem_pkcs8(EVP_PKEY* key) {
  Bio b = memory_bio();
  check(PEM_write_bio_PKCS8PrivateKey(b.get(), key, nullptr, nullptr, 0, nullptr, nullptr),
        "PEM_write_bio_PKCS8PrivateKey");
  return text_of(b.get());
}

Cert read_cert(const std::filesystem::path& file) {
  const std::string text = read_text(file);  // the BIO reads it in place
  Bio b = memory_bio(text);
  X509* c = PEM_read_bio_X509(b.get(), nullptr, nullptr, nullptr);
  if (c == nullptr) throw std::runtime_error(last_error(file.string() + ": not a PEM certificate"));
  return Cert(c);
}

Key read_key(const std::filesystem::path& file) {
  const std::string text = read_text(file);
  Bio b = memory_bio(text);
  EVP_PKEY* k = PEM_read_bio_PrivateKey(b.get(), nullptr, nullptr, nullptr);
  if (k == nullptr)
    throw std::runtime_error(last_error(file.string() + ": not an unencrypted PEM private key"));
  return Key(k);
}

std::string smime_sign(const std::string& text, X509* cert, EVP_PKEY* key) {
  constexpr int flags = PKCS7_DETACHED | PKCS7_TEXT;
  Bio in = memory_bio(text);
  std::unique_ptr<PKCS7, FreePkcs7> p7(check(PKCS7_sign(cert, key, nullptr, in.get(), flags), "PKCS7_sign"));
  // PKCS7_sign consumed `in`; the clear-signed document repeats the text beside the signature.
  Bio again = memory_bio(text);
  Bio out = memory_bio();
  check(SMIME_write_PKCS7(out.get(), p7.get(), again.get(), flags), "SMIME_write_PKCS7");
  return text_of(out.get());
}

std::string smime_verify(const std::string& document, X509* ca) {
  Bio in = memory_bio(document);
  BIO* content = nullptr;
  std::unique_ptr<PKCS7, FreePkcs7> p7(SMIME_read_PKCS7(in.get(), &content));
  Bio content_owner(content);
  if (p7 == nullptr) throw std::runtime_error(last_error("not an S/MIME signed document"));
  std::unique_ptr<X509_STORE, FreeStore> store(check(X509_STORE_new(), "X509_STORE_new"));
  check(X509_STORE_add_cert(store.get(), ca), "X509_STORE_add_cert");
  Bio out = memory_bio();
  if (PKCS7_verify(p7.get(), nullptr, store.get(), content, out.get(), PKCS7_TEXT) != 1)
    throw std::runtime_error(last_error("signature not verified"));
  return text_of(out.get());
}

TimePoint not_before(X509* cert) { return time_of(X509_get0_notBefore(cert)); }
TimePoint not_after(X509* cert) { return time_of(X509_get0_notAfter(cert)); }
std::string subject(X509* cert) { return name_text(X509_get_subject_name(cert)); }
std::string issuer(X509* cert) { return name_text(X509_get_issuer_name(cert)); }

std::string verify_issued_by(X509* cert, X509* ca) {
  std::unique_ptr<X509_STORE, FreeStore> store(check(X509_STORE_new(), "X509_STORE_new"));
  check(X509_STORE_add_cert(store.get(), ca), "X509_STORE_add_cert");
  std::unique_ptr<X509_STORE_CTX, FreeStoreCtx> ctx(check(X509_STORE_CTX_new(), "X509_STORE_CTX_new"));
  check(X509_STORE_CTX_init(ctx.get(), store.get(), cert, nullptr), "X509_STORE_CTX_init");
  if (X509_verify_cert(ctx.get()) == 1) return "";
  ERR_clear_error();
  return X509_verify_cert_error_string(X509_STORE_CTX_get_error(ctx.get()));
}

Crl read_crl(const std::filesystem::path& file) {
  const std::string text = read_text(file);
  Bio b = memory_bio(text);
  X509_CRL* c = PEM_read_bio_X509_CRL(b.get(), nullptr, nullptr, nullptr);
  if (c == nullptr) throw std::runtime_error(last_error(file.filename().string() + ": not a PEM CRL"));
  return Crl(c);
}

std::string pem(X509_CRL* crl) {
  Bio b = memory_bio();
  check(PEM_write_bio_X509_CRL(b.get(), crl), "PEM_write_bio_X509_CRL");
  return text_of(b.get());
}

std::string serial_hex(X509* cert) {
  std::unique_ptr<BIGNUM, decltype(&BN_free)> bn(
      check(ASN1_INTEGER_to_BN(X509_get0_serialNumber(cert), nullptr), "ASN1_INTEGER_to_BN"), BN_free);
  char* hex = check(BN_bn2hex(bn.get()), "BN_bn2hex");
  std::string out(hex);
  OPENSSL_free(hex);
  return out;
}

Crl make_crl(X509* ca, EVP_PKEY* ca_key, const std::vector<std::pair<std::string, TimePoint>>& entries,
             TimePoint next) {
  Crl crl(check(X509_CRL_new(), "X509_CRL_new"));
  check(X509_CRL_set_version(crl.get(), 1), "X509_CRL_set_version");  // v2
  check(X509_CRL_set_issuer_name(crl.get(), X509_get_subject_name(ca)), "X509_CRL_set_issuer_name");
  auto asn1_time = [](TimePoint t) {
    return std::unique_ptr<ASN1_TIME, FreeAsn1Time>(
        check(ASN1_TIME_set(nullptr, std::chrono::system_clock::to_time_t(t)), "ASN1_TIME_set"));
  };
  // A day back, as certificates start: a host whose clock is a little behind must not see a
  // CRL "not yet valid", which would make DDS Security refuse every peer.
  check(X509_CRL_set1_lastUpdate(crl.get(),
                                 asn1_time(std::chrono::system_clock::now() - std::chrono::hours(24)).get()),
        "lastUpdate");
  check(X509_CRL_set1_nextUpdate(crl.get(), asn1_time(next).get()), "nextUpdate");
  for (const auto& [serial, when] : entries) {
    X509_REVOKED* r = check(X509_REVOKED_new(), "X509_REVOKED_new");
    BIGNUM* bn = nullptr;
    if (BN_hex2bn(&bn, serial.c_str()) == 0) {
      X509_REVOKED_free(r);
      fail("serial " + serial);
    }
    ASN1_INTEGER* n = BN_to_ASN1_INTEGER(bn, nullptr);
    BN_free(bn);
    const int ok = n != nullptr && X509_REVOKED_set_serialNumber(r, n) == 1 &&
                   X509_REVOKED_set_revocationDate(r, asn1_time(when).get()) == 1;
    ASN1_INTEGER_free(n);
    if (!ok || X509_CRL_add0_revoked(crl.get(), r) != 1) {
      X509_REVOKED_free(r);
      fail("X509_CRL_add0_revoked");
    }
  }
  check(X509_CRL_sort(crl.get()), "X509_CRL_sort");
  // Names the issuing CA's key (or its name and serial, for a CA without a key identifier).
  X509V3_CTX ctx;
  X509V3_set_ctx(&ctx, ca, nullptr, nullptr, crl.get(), 0);
  X509_EXTENSION* ext =
      check(X509V3_EXT_conf_nid(nullptr, &ctx, NID_authority_key_identifier, "keyid,issuer"),
            "CRL authorityKeyIdentifier");
  const int added = X509_CRL_add_ext(crl.get(), ext, -1);
  X509_EXTENSION_free(ext);
  check(added == 1 ? 1 : 0, "X509_CRL_add_ext");
  if (X509_CRL_sign(crl.get(), ca_key, EVP_sha256()) <= 0) fail("X509_CRL_sign");
  return crl;
}

std::vector<std::pair<std::string, TimePoint>> revoked(X509_CRL* crl) {
  std::vector<std::pair<std::string, TimePoint>> out;
  STACK_OF(X509_REVOKED)* list = X509_CRL_get_REVOKED(crl);
  for (int i = 0; i < sk_X509_REVOKED_num(list); ++i) {
    const X509_REVOKED* r = sk_X509_REVOKED_value(list, i);
    std::unique_ptr<BIGNUM, decltype(&BN_free)> bn(
        check(ASN1_INTEGER_to_BN(X509_REVOKED_get0_serialNumber(r), nullptr), "ASN1_INTEGER_to_BN"), BN_free);
    char* hex = check(BN_bn2hex(bn.get()), "BN_bn2hex");
    out.emplace_back(hex, time_of(X509_REVOKED_get0_revocationDate(r)));
    OPENSSL_free(hex);
  }
  return out;
}

bool crl_signed_by(X509_CRL* crl, X509* ca) {
  EVP_PKEY* key = X509_get0_pubkey(ca);
  const bool ok = key != nullptr && X509_CRL_verify(crl, key) == 1 &&
                  X509_NAME_cmp(X509_CRL_get_issuer(crl), X509_get_subject_name(ca)) == 0;
  ERR_clear_error();
  return ok;
}

TimePoint next_update(X509_CRL* crl) {
  const ASN1_TIME* t = X509_CRL_get0_nextUpdate(crl);
  return t == nullptr ? TimePoint{} : time_of(t);
}

}  // namespace saw::security::ossl

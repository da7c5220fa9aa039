#include "handshake_order.hpp"

#include <openssl/evp.h>
#include <openssl/x509.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

#include "openssl.hpp"

namespace saw::security::ossl {

namespace {

constexpr std::size_t kSerialChars = 16;  // hex digits: 64 bits of search space

struct FreeName {
  void operator()(X509_NAME* p) const noexcept { X509_NAME_free(p); }
};
struct FreeMdCtx {
  void operator()(EVP_MD_CTX* p) const noexcept { EVP_MD_CTX_free(p); }
};
struct FreeMd {
  void operator()(EVP_MD* p) const noexcept { EVP_MD_free(p); }
};

// The DER encoding of the subject exactly as make_certificate builds it.
std::vector<unsigned char> subject_der(const std::string& common_name, const std::string& serial) {
  std::unique_ptr<X509_NAME, FreeName> name(X509_NAME_new());
  if (!name) throw std::runtime_error(last_error("X509_NAME_new"));
  add_subject_entries(name.get(), common_name, serial);
  unsigned char* der = nullptr;
  const int n = i2d_X509_NAME(name.get(), &der);
  if (n <= 0) throw std::runtime_error(last_error("i2d_X509_NAME"));
  std::vector<unsigned char> out(der, der + n);
  OPENSSL_free(der);
  return out;
}

int leading_ones(const unsigned char* md) {
  int bits = 0;
  for (int i = 0; i < 32; ++i) {
    if (md[i] == 0xff) {
      bits += 8;
      continue;
    }
    for (unsigned char m = 0x80; m != 0 && (md[i] & m) != 0; m >>= 1) ++bits;
    break;
  }
  return bits;
}

}  // namespace

int order_bits(const std::string& common_name, const std::string& serial) {
  const std::vector<unsigned char> der = subject_der(common_name, serial);
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  if (EVP_Digest(der.data(), der.size(), md, &len, EVP_sha256(), nullptr) != 1)
    throw std::runtime_error(last_error("SHA-256"));
  return leading_ones(md);
}

int order_bits(X509* cert) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  if (X509_NAME_digest(X509_get_subject_name(cert), EVP_sha256(), md, &len) != 1)
    throw std::runtime_error(last_error("SHA-256 of the subject"));
  return leading_ones(md);
}

std::string high_order_serial(const std::string& common_name) {
  static constexpr char hex[] = "0123456789ABCDEF";
  std::string serial(kSerialChars, '0');
  std::vector<unsigned char> der = subject_der(common_name, serial);
  // The serial's characters sit at the end of the encoding (the last attribute's value), so
  // each candidate is written in place rather than encoded again.
  const std::size_t at = der.size() - kSerialChars;
  if (!std::equal(serial.begin(), serial.end(), der.begin() + static_cast<std::ptrdiff_t>(at)))
    throw std::runtime_error("subject encoding: the serialNumber is not where expected");
  std::unique_ptr<EVP_MD, FreeMd> sha256(EVP_MD_fetch(nullptr, "SHA256", nullptr));
  std::unique_ptr<EVP_MD_CTX, FreeMdCtx> ctx(EVP_MD_CTX_new());
  if (!sha256 || !ctx) throw std::runtime_error(last_error("SHA-256"));
  unsigned char md[EVP_MAX_MD_SIZE];
  for (std::uint64_t i = 0;; ++i) {
    for (std::size_t k = 0; k < kSerialChars; ++k)
      der[at + k] = hex[(i >> (4 * (kSerialChars - 1 - k))) & 0xf];
    unsigned int len = 0;
    if (EVP_DigestInit_ex2(ctx.get(), sha256.get(), nullptr) != 1 ||
        EVP_DigestUpdate(ctx.get(), der.data(), der.size()) != 1 ||
        EVP_DigestFinal_ex(ctx.get(), md, &len) != 1)
      throw std::runtime_error(last_error("SHA-256"));
    if (leading_ones(md) >= kOrderBits)
      return std::string(reinterpret_cast<const char*>(der.data() + at), kSerialChars);
  }
}

}  // namespace saw::security::ossl

// Handshake order: a certificate subject chosen so that its holder never starts a DDS Security handshake.
#pragma once

#include <openssl/x509.h>

#include <string>

namespace saw::security::ossl {

// DDS Security derives a participant's GUID prefix from SHA-256 of its certificate's subject
// (DER), and the participant with the lower GUID starts the authentication handshake. Fast DDS 2.9
// starts it with DH+MODP-2048-256, its public key as raw octets, which Cyclone DDS 0.10 reads as a
// DER INTEGER and refuses; a handshake Cyclone DDS starts (ECDH) works both ways. So the
// certificates of our Fast DDS servers (gateways) get a subject CN=COMMON_NAME, serialNumber=S
// whose hash begins with `kOrderBits` one bits: a peer whose subject hashes higher still (about
// one name in 2^(kOrderBits+1)) is the only one left that Fast DDS would greet first. 22 bits: about
// 4 million hashes at enrolment (about a second), one peer name in 8 million left out.
inline constexpr int kOrderBits = 22;

// The serialNumber attribute value S for `common_name` (found by search; ~2^kOrderBits hashes).
std::string high_order_serial(const std::string& common_name);

// The number of leading one bits of SHA-256 of the DER encoding of CN=common_name[, serialNumber=serial].
int order_bits(const std::string& common_name, const std::string& serial);
// The same of a certificate's subject as it is encoded (as DDS Security hashes it).
int order_bits(X509* cert);

}  // namespace saw::security::ossl

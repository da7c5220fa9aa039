// Keystore fixture: a fresh keystore in a temporary directory, removed after the test.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

#include "saw/security/keystore.hpp"

namespace saw::testing {

struct TempKeystore {
  explicit TempKeystore(const std::string& tag, const security::KeystoreOptions& o = {}) {
    dir = std::filesystem::temp_directory_path() / ("saw-ks-" + tag + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    security::create_keystore(dir, o);
  }
  ~TempKeystore() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
  TempKeystore(const TempKeystore&) = delete;
  TempKeystore& operator=(const TempKeystore&) = delete;

  std::filesystem::path enroll(const std::string& name, security::Role role) const {
    security::EnrollOptions o;
    o.role = role;
    return security::enroll(dir, name, o);
  }

  std::filesystem::path dir;
};

}  // namespace saw::testing

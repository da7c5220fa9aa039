// ConfigError: a deployment-file error, always naming file, line, column and key.
#pragma once

#include <stdexcept>
#include <string>

namespace saw::deploy {

class ConfigError : public std::runtime_error {
 public:
  // Line and column are 1-based; 0 when unknown.
  ConfigError(const std::string& file, int line, int column, const std::string& key, const std::string& what)
      : std::runtime_error(file + ":" + std::to_string(line) + ":" + std::to_string(column) + ": key '" + key +
                           "': " + what) {}
};

}  // namespace saw::deploy

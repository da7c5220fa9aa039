// Deployment texts in the deploy tests: a shipped file read whole, and edited by replacement.
#pragma once

#include <fstream>
#include <sstream>
#include <string>

namespace saw::testing {

inline std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (auto at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
    s.replace(at, from.size(), to);
  return s;
}

}  // namespace saw::testing

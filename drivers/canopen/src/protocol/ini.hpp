// The INI dialect of CiA 306 files: sections, key=value lines, ';' comments, keys and section
// names compared without case. Every value remembers its line and column for error messages.
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace saw::canopen::ini {

struct Value {
  std::string key;   // as written
  std::string text;  // trimmed
  int line = 0;
  int column = 0;  // 1-based column of the value's first character
};

struct Section {
  std::string name;  // as written
  int line = 0;
  std::map<std::string, Value> values;            // by lower-case key
  const Value* find(std::string_view key) const;  // `key` in lower case
};

struct File {
  std::string path;
  std::vector<Section> sections;                     // in file order
  std::map<std::string, std::size_t> by_name;        // lower-case name -> index
  const Section* find(std::string_view name) const;  // `name` in lower case
};

std::string lower(std::string_view s);

// Throws saw::deploy::ConfigError naming path:line: a line outside any section, a line that
// is not key=value, a section or a key given twice, an unterminated section header.
File parse(std::string_view text, const std::string& path);

}  // namespace saw::canopen::ini

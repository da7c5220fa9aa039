#include "ini.hpp"

#include <algorithm>
#include <cctype>

#include "saw/deploy/config_error.hpp"

namespace saw::canopen::ini {

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

const Value* Section::find(std::string_view key) const {
  const auto it = values.find(std::string(key));
  return it == values.end() ? nullptr : &it->second;
}

const Section* File::find(std::string_view name) const {
  const auto it = by_name.find(std::string(name));
  return it == by_name.end() ? nullptr : &sections[it->second];
}

namespace {

bool space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// Trims `s`, returning how many characters were cut from the front.
std::size_t trim(std::string_view& s) {
  std::size_t front = 0;
  while (!s.empty() && space(s.front())) {
    s.remove_prefix(1);
    ++front;
  }
  while (!s.empty() && space(s.back())) s.remove_suffix(1);
  return front;
}

}  // namespace

File parse(std::string_view text, const std::string& path) {
  File file;
  file.path = path;
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);  // a UTF-8 byte-order mark
  int line_number = 0;
  for (std::size_t pos = 0; pos < text.size();) {
    ++line_number;
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    const std::size_t indent = trim(line);
    if (line.empty() || line.front() == ';' || line.front() == '#') continue;
    const int column = static_cast<int>(indent) + 1;
    if (line.front() == '[') {
      const std::size_t close = line.find(']');
      if (close == std::string_view::npos)
        throw deploy::ConfigError(path, line_number, column, std::string(line), "section header without ']'");
      std::string_view name = line.substr(1, close - 1);
      trim(name);
      const std::string key = lower(name);
      if (const Section* first = file.find(key))
        throw deploy::ConfigError(path, line_number, column, "[" + std::string(name) + "]",
                                  "section given twice (first on line " + std::to_string(first->line) + ")");
      file.by_name.emplace(key, file.sections.size());
      file.sections.push_back(Section{std::string(name), line_number, {}});
    } else {
      const std::size_t eq = line.find('=');
      if (file.sections.empty()) {
        // The key, or the line itself when there is none ("=x"): an error always names one.
        std::string_view key = line.substr(0, eq);
        trim(key);
        throw deploy::ConfigError(path, line_number, column, std::string(key.empty() ? line : key),
                                  "outside any section");
      }
      Section& section = file.sections.back();
      if (eq == std::string_view::npos)
        throw deploy::ConfigError(path, line_number, column, "[" + section.name + "]",
                                  "'" + std::string(line) + "' is not key=value");
      std::string_view key = line.substr(0, eq);
      trim(key);
      std::string_view value = line.substr(eq + 1);
      const std::size_t value_front = trim(value);
      if (key.empty())
        throw deploy::ConfigError(path, line_number, column, "[" + section.name + "]",
                                  "a value without a key");
      const std::string lkey = lower(key);
      const std::string where = section.name + "." + std::string(key);
      if (const Value* first = section.find(lkey))
        throw deploy::ConfigError(
            path, line_number, column, where,
            "key given twice in [" + section.name + "] (first on line " + std::to_string(first->line) + ")");
      const int value_column = static_cast<int>(indent + eq + 1 + value_front) + 1;
      section.values.emplace(lkey, Value{std::string(key), std::string(value), line_number, value_column});
    }
  }
  return file;
}

}  // namespace saw::canopen::ini

// ConfigError: a deployment-file error, always naming file, line, column and key.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace saw::deploy {

// Where in a deployment file something is: 1-based line and column, 0 when unknown.
struct Location {
  std::string file;
  int line = 0;
  int column = 0;
  std::string key;  // dotted path, e.g. "components[2].params.gains.master"
};

// what() is "<file>:<line>:<column>: key '<key>': <problem>", one such line per problem, so an
// editor or a CI log can jump to each. The accessors describe the first problem.
class ConfigError : public std::runtime_error {
 public:
  struct Problem {
    Location where;
    std::string what;
  };

  ConfigError(const std::string& file, int line, int column, const std::string& key, const std::string& what)
      : ConfigError(std::vector<Problem>{{{file, line, column, key}, what}}) {}
  ConfigError(const Location& where, const std::string& what)
      : ConfigError(std::vector<Problem>{{where, what}}) {}
  // `problems` must not be empty.
  explicit ConfigError(std::vector<Problem> problems)
      : std::runtime_error(format(problems)), problems_(std::move(problems)) {}

  const std::string& file() const noexcept { return problems_.front().where.file; }
  int line() const noexcept { return problems_.front().where.line; }
  int column() const noexcept { return problems_.front().where.column; }
  const std::string& key() const noexcept { return problems_.front().where.key; }
  const std::vector<Problem>& problems() const noexcept { return problems_; }

 private:
  static std::string format(const std::vector<Problem>& problems) {
    std::string out;
    for (const auto& p : problems) {
      if (!out.empty()) out += '\n';
      out += p.where.file + ":" + std::to_string(p.where.line) + ":" + std::to_string(p.where.column) +
             ": key '" + p.where.key + "': " + p.what;
    }
    return out;
  }

  std::vector<Problem> problems_;
};

}  // namespace saw::deploy

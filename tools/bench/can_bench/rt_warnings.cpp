#include "rt_warnings.hpp"

#include <algorithm>

namespace saw::bench::can_bench {
namespace {

std::vector<std::string> warnings;

}  // namespace

void note_warnings(const saw::Manager& m) {
  for (const auto& w : m.rt_warnings())
    if (std::find(warnings.begin(), warnings.end(), w) == warnings.end()) warnings.push_back(w);
}

const std::vector<std::string>& rt_warnings() { return warnings; }

}  // namespace saw::bench::can_bench

#include "saw/teleop/law_registry.hpp"

#include <algorithm>
#include <stdexcept>

namespace saw::teleop {

const std::vector<std::string>& LawRegistry::reserved() {
  static const std::vector<std::string> keys{"law", "stale_timeout", "startup_timeout", "device_timeout",
                                             "start_enabled"};
  return keys;
}

void LawRegistry::add_entry(std::string name, Entry e) {
  if (const auto it = laws_.find(name); it != laws_.end() && it->second.identity == e.identity) return;
  if (laws_.count(name) != 0)
    throw std::invalid_argument("teleoperation law '" + name + "' registered twice");
  for (const auto& r : e.rows)
    if (std::find(reserved().begin(), reserved().end(), r.name) != reserved().end())
      throw std::invalid_argument("teleoperation law '" + name + "': setting '" + r.name +
                                  "' is one of the task's own parameters");
  laws_.emplace(std::move(name), std::move(e));
}

const LawRegistry::Entry* LawRegistry::find(const std::string& name) const {
  const auto it = laws_.find(name);
  return it == laws_.end() ? nullptr : &it->second;
}

std::string LawRegistry::names() const {
  std::string out;
  for (const auto& [name, e] : laws_) out += (out.empty() ? "" : ", ") + name;
  return out;
}

std::string LawRegistry::markdown() const {
  std::string out;
  for (const auto& [name, e] : laws_) {
    out += "### `law: " + name + "`\n\n" + e.description + ".\n\n";
    out += "| setting | value | unit | bounds | default | run-time command | what it is |\n";
    out += "|---|---|---|---|---|---|---|\n";
    for (const auto& r : e.rows) {
      const auto code = [](const std::string& s) { return s.empty() ? std::string("—") : "`" + s + "`"; };
      out += "| `" + r.name + "` | " + r.shape + " | " + (r.unit.empty() ? "—" : r.unit) + " | " +
             (r.bounds.empty() ? "—" : r.bounds) + " | `" + r.fallback + "` | " + code(r.command) + " | " +
             r.help + " |\n";
    }
    if (!e.readouts.empty()) {
      out += "\nRead-outs (state, read commands): ";
      for (std::size_t i = 0; i < e.readouts.size(); ++i) {
        const auto& r = e.readouts[i];
        out += (i ? "; " : "") + ("`" + r.name + "`") + (r.unit.empty() ? "" : " (" + r.unit + ")") + ", " +
               r.help;
      }
      out += ".\n";
    }
    out += "\n";
  }
  return out;
}

}  // namespace saw::teleop

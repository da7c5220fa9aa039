#include "saw/deploy/registry.hpp"

#include <dlfcn.h>
#include <sys/stat.h>

#include <cstdio>
#include <stdexcept>

#include "saw/deploy/plugin.hpp"
#include "saw/device.hpp"

namespace saw::deploy {

namespace {

// A device's contract in a run's summary: a FAULT and its output, what was refused, when commands
// stopped, the last fault.
std::string device_summary(const DeviceStatus& s) {
  std::string out;
  char b[240];
  if (s.state == OperatingStateValue::fault)
    out =
        std::string("FAULT, its last output ") +
        (s.safe_output ? "the safe one (" + std::string(to_string(s.safe_state)) + ")" : "NOT the safe one");
  const RefusedCommands& r = s.refused;
  if (r.total() != 0) {
    std::snprintf(
        b, sizeof b,
        "%s%llu servo commands refused before the hardware: %llu not finite, %llu over a limit, "
        "%llu of another mode, %llu of the wrong size",
        out.empty() ? "" : "\n", static_cast<unsigned long long>(r.total()),
        static_cast<unsigned long long>(r.not_finite), static_cast<unsigned long long>(r.over_limit),
        static_cast<unsigned long long>(r.wrong_mode), static_cast<unsigned long long>(r.wrong_size));
    out += b;
  }
  if (s.watchdog_trips != 0) {
    std::snprintf(
        b, sizeof b, "%scommands stopped %llu times: %s after %.1f ms without one (command_timeout)",
        out.empty() ? "" : "\n", static_cast<unsigned long long>(s.watchdog_trips),
        std::string(to_string(s.safe_state)).c_str(), static_cast<double>(s.command_timeout) * 1e-6);
    out += b;
  }
  if (s.faults != 0) {
    out += (out.empty() ? "" : "\n") + std::to_string(s.faults) + " faults; the last: " + to_string(s.fault);
    if (!s.reason_text().empty()) out += " — " + std::string(s.reason_text());
  }
  return out;
}

}  // namespace

ComponentRegistry::ComponentRegistry() { add_summary_format<DeviceStatus>(device_summary); }

void ComponentRegistry::add_type(std::string type, Type t) {
  if (const auto it = types_.find(type); it != types_.end())
    throw std::logic_error("component type '" + type + "' registered twice (" +
                           (it->second.origin.empty() ? "built in" : "by " + it->second.origin) + ", then " +
                           (loading_.empty() ? "built in" : "by " + loading_) + ")");
  t.origin = loading_;
  types_.emplace(std::move(type), std::move(t));
}

TaskConfig periodic_task(const ComponentContext& ctx, const Params& params, const std::string& type) {
  const TaskConfig t = ctx.task.value_or(TaskConfig::periodic(std::chrono::milliseconds(1), 80));
  if (!t.is_periodic()) params.fail(type + " '" + ctx.name + "' needs a periodic task (task.period)");
  return t;
}

void ComponentRegistry::add_section(std::string key, Section section) {
  if (const auto it = section_origins_.find(key); it != section_origins_.end())
    throw std::invalid_argument("deployment section '" + key + "' is registered already (by " +
                                (it->second.empty() ? std::string("saw-rt") : it->second) + "; now by " +
                                (loading_.empty() ? std::string("saw-rt") : loading_) + ")");
  section_origins_[key] = loading_;
  sections_.emplace(std::move(key), std::move(section));
}

const Section* ComponentRegistry::find_section(const std::string& key) const {
  const auto it = sections_.find(key);
  return it == sections_.end() ? nullptr : &it->second;
}

const ComponentRegistry::Type* ComponentRegistry::find(const std::string& type) const {
  const auto it = types_.find(type);
  return it == types_.end() ? nullptr : &it->second;
}

std::string ComponentRegistry::type_list() const {
  std::string out;
  for (const auto& [name, entry] : types_) out += (out.empty() ? "" : ", ") + name;
  return out;
}

const SummaryFormat* ComponentRegistry::summary_format(TypeInfo type) const {
  const auto it = summary_formats_.find(std::string(type.name));
  return it == summary_formats_.end() ? nullptr : &it->second;
}

void ComponentRegistry::load_plugin(const std::string& path) {
  if (!plugins_allowed_) throw std::runtime_error("plug-ins are not loaded by this program");
  for (const auto& p : plugins_)
    if (p == path) return;  // named by two files of one run: once is enough
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) throw std::runtime_error("no such file: " + path);
  // RTLD_NOW: an unresolved symbol is an error here, not a crash in the middle of a run.
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) throw std::runtime_error(std::string("cannot load: ") + dlerror());
  using AbiFn = std::uint32_t (*)();
  using RegisterFn = void (*)(ComponentRegistry&);
  const auto abi = reinterpret_cast<AbiFn>(dlsym(handle, "saw_plugin_abi_version"));
  const auto reg = reinterpret_cast<RegisterFn>(dlsym(handle, "saw_plugin_register"));
  if (abi == nullptr || reg == nullptr) {
    dlclose(handle);
    throw std::runtime_error(path +
                             " is not a sawrt plug-in (no saw_plugin_abi_version/saw_plugin_register; "
                             "see SAW_PLUGIN in saw/deploy/plugin.hpp)");
  }
  if (const auto v = abi(); v != plugin_abi_version) {
    dlclose(handle);
    throw std::runtime_error(path + " was built for sawrt plug-in ABI version " + std::to_string(v) +
                             "; this program has ABI version " + std::to_string(plugin_abi_version) +
                             ": rebuild it against this sawrt");
  }
  loading_ = path;
  try {
    reg(*this);
  } catch (...) {
    loading_.clear();
    throw;  // its types may be half registered; the run stops here anyway
  }
  loading_.clear();
  plugins_.push_back(path);
  // Never dlclose'd: components, formatters and their destructors live in its code.
}

}  // namespace saw::deploy

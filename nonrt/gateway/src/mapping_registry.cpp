// MappingRegistry: the process's DDS mappings, the core's and those of the mapping modules loaded.
#include <dlfcn.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <system_error>

#include "core_mappings.hpp"
#include "saw/crtk.hpp"
#include "saw/description.hpp"
#include "saw/gateway/mapping_plugin.hpp"
#include "saw/gateway/type_map.hpp"
#include "saw/type_info.hpp"

namespace saw::gateway {
namespace fs = std::filesystem;

void MappingRegistry::add(std::unique_ptr<Mapping> m) {
  if (const Mapping* had = find(m->saw_type()); had != nullptr) {
    if (had->dds_type() == m->dds_type() && had->saw_version() == m->saw_version()) return;
    throw std::invalid_argument(std::string(m->saw_type()) + " is mapped to " + std::string(had->dds_type()) +
                                " already; a second mapping to " + std::string(m->dds_type()) +
                                " (layout version " + std::to_string(m->saw_version()) + ") is refused");
  }
  mappings_.push_back(std::move(m));
}

const Mapping* MappingRegistry::find(std::string_view saw_type) const {
  for (const auto& m : mappings_)
    if (m->saw_type() == saw_type) return m.get();
  return nullptr;
}

const Mapping* MappingRegistry::find_by_dds(std::string_view dds_type) const {
  for (const auto& m : mappings_)
    if (m->dds_type() == dds_type) return m.get();
  if (dds_type == empty_mapping().dds_type()) return &empty_mapping();
  return nullptr;
}

MappingRegistry core_mappings() {
  MappingRegistry core;
  register_core_mappings(core);
  return core;
}

std::vector<std::string> mapping_directories() {
  std::vector<std::string> dirs;
  std::error_code ec;
  const fs::path bin = fs::read_symlink("/proc/self/exe", ec).parent_path();
  for (const fs::path& candidate :
       {bin / ".." / "lib" / "sawrt" / "mappings", bin / ".." / SAW_INSTALL_LIBDIR / "sawrt" / "mappings"}) {
    const fs::path dir = fs::weakly_canonical(candidate, ec);
    if (!ec && fs::is_directory(dir) && std::find(dirs.begin(), dirs.end(), dir.string()) == dirs.end())
      dirs.push_back(dir.string());
  }
  // A lab's modules, besides the installation's (a lab's module adds its types; it replaces none).
  if (const char* env = std::getenv("SAW_MAPPING_PATH"); env != nullptr) {
    const std::string list = env;
    for (std::size_t start = 0; start <= list.size();) {
      const auto end = std::min(list.find(':', start), list.size());
      if (end > start) dirs.push_back(list.substr(start, end - start));
      start = end + 1;
    }
  }
  return dirs;
}

namespace {

void load_module(const std::string& path, MappingRegistry& registry) {
  // RTLD_NOW: an unresolved symbol is an error here, not a crash when a sample arrives.
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) throw std::runtime_error(std::string("cannot load: ") + dlerror());
  using AbiFn = std::uint32_t (*)();
  using RegisterFn = void (*)(MappingRegistry&);
  const auto abi = reinterpret_cast<AbiFn>(dlsym(handle, "saw_mapping_abi_version"));
  const auto reg = reinterpret_cast<RegisterFn>(dlsym(handle, "saw_mapping_register"));
  if (abi == nullptr || reg == nullptr) {
    dlclose(handle);
    throw std::runtime_error(
        "not a mapping module (no saw_mapping_abi_version/saw_mapping_register; see SAW_MAPPINGS in "
        "saw/gateway/mapping_plugin.hpp)");
  }
  if (const auto v = abi(); v != mapping_abi_version) {
    dlclose(handle);
    throw std::runtime_error("built for mapping ABI version " + std::to_string(v) + "; this program has " +
                             std::to_string(mapping_abi_version) + ": rebuild it against this sawrt");
  }
  reg(registry);
  // Never dlclose'd: the mappings' code lives in it.
}

}  // namespace

void load_mapping_modules(MappingRegistry& registry) {
  for (const std::string& dir : mapping_directories()) {
    std::error_code ec;
    std::vector<fs::path> modules;
    for (const auto& entry : fs::directory_iterator(dir, ec))
      if (entry.path().extension() == ".so" && entry.path().filename().string().rfind("lib", 0) == 0)
        modules.push_back(entry.path());
    if (ec) throw std::runtime_error("mapping directory " + dir + ": " + ec.message());
    std::sort(modules.begin(), modules.end());
    for (const fs::path& m : modules) {
      try {
        load_module(m.string(), registry);
      } catch (const std::exception& e) {
        throw std::runtime_error("mapping module " + m.string() + ": " + e.what());
      }
    }
  }
}

bool within_limits(const Mapping& m, const void* value, const Limits& limits, std::string& why) {
  if (m.check(value, limits)) return true;
  std::vector<double> shown;
  m.numbers(value, shown);
  char b[160];
  const auto outside = std::find_if(shown.begin(), shown.end(),
                                    [&](double x) { return !(x >= limits.min && x <= limits.max); });
  if (outside != shown.end())
    std::snprintf(b, sizeof b, "%g is outside [%g, %g], the range the component declares", *outside,
                  limits.min, limits.max);
  else
    std::snprintf(b, sizeof b, "a number of the value is outside [%g, %g], the range the component declares",
                  limits.min, limits.max);
  why = b;
  return false;
}

bool latched(const Mapping* m) {
  return m != nullptr && (m->saw_type() == type_info_of<OperatingState>().name ||
                          m->saw_type() == type_info_of<ComponentDescription>().name);
}

std::int64_t wall_from_monotonic(TimeNs monotonic) {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  const std::int64_t wall = static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
  return wall - (monotonic_now() - monotonic);
}

}  // namespace saw::gateway

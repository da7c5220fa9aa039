#include "packages.hpp"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <system_error>

namespace saw::apps {
namespace fs = std::filesystem;

std::vector<fs::path> package_directories() {
  std::vector<fs::path> dirs;
  if (const char* env = std::getenv("SAW_PACKAGE_PATH"); env != nullptr) {
    std::string list = env;
    for (std::size_t start = 0; start <= list.size();) {
      const auto end = std::min(list.find(':', start), list.size());
      if (end > start) dirs.emplace_back(list.substr(start, end - start));
      start = end + 1;
    }
    return dirs;
  }
  std::error_code ec;
  const fs::path bin = fs::read_symlink("/proc/self/exe", ec).parent_path();
  for (const fs::path& candidate :
       {bin / ".." / "lib" / "sawrt" / "packages", bin / ".." / SAW_INSTALL_LIBDIR / "sawrt" / "packages"}) {
    const fs::path dir = fs::weakly_canonical(candidate, ec);
    if (!ec && fs::is_directory(dir) && std::find(dirs.begin(), dirs.end(), dir) == dirs.end())
      dirs.push_back(dir);
  }
  return dirs;
}

void load_packages(deploy::ComponentRegistry& registry) {
  const auto dirs = package_directories();
  if (dirs.empty())
    throw std::runtime_error(
        "no package directory: neither $SAW_PACKAGE_PATH nor lib/sawrt/packages beside "
        "this program (a broken installation?)");
  for (const fs::path& dir : dirs) {
    std::error_code ec;
    std::vector<fs::path> modules;
    for (const auto& entry : fs::directory_iterator(dir, ec))
      if (entry.path().extension() == ".so" && entry.path().filename().string().rfind("lib", 0) == 0)
        modules.push_back(entry.path());
    if (ec) throw std::runtime_error("package directory " + dir.string() + ": " + ec.message());
    std::sort(modules.begin(), modules.end());
    for (const fs::path& m : modules) {
      try {
        registry.load_plugin(m.string());
      } catch (const std::exception& e) {
        throw std::runtime_error("package " + m.string() + ": " + e.what());
      }
    }
  }
}

}  // namespace saw::apps

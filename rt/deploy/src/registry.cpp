#include "saw/deploy/registry.hpp"

#include <stdexcept>

namespace saw::deploy {

void ComponentRegistry::add(std::string type, Factory factory, std::string description) {
  if (types_.count(type)) throw std::logic_error("component type '" + type + "' registered twice");
  types_.emplace(std::move(type), std::make_pair(std::move(factory), std::move(description)));
}

const Factory* ComponentRegistry::find(const std::string& type) const {
  const auto it = types_.find(type);
  return it == types_.end() ? nullptr : &it->second.first;
}

std::string ComponentRegistry::type_list() const {
  std::string out;
  for (const auto& [name, entry] : types_) out += (out.empty() ? "" : ", ") + name;
  return out;
}

}  // namespace saw::deploy

// ComponentRegistry: the component types a deployment file may name, and how to build each.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "saw/component.hpp"
#include "saw/deploy/params.hpp"
#include "saw/task.hpp"

namespace saw::deploy {

// What a factory gets: the component's name, its task block (absent → the type's default),
// its parameters, and the directory of the deployment file (for relative paths).
struct FactoryContext {
  std::string name;
  std::optional<TaskConfig> task;
  Params& params;
  std::string directory;
};

using Factory = std::function<std::unique_ptr<Component>(FactoryContext&)>;

class ComponentRegistry {
 public:
  void add(std::string type, Factory factory, std::string description);
  const Factory* find(const std::string& type) const;
  // "a, b, c": for error messages.
  std::string type_list() const;
  const std::map<std::string, std::pair<Factory, std::string>>& types() const noexcept { return types_; }

 private:
  std::map<std::string, std::pair<Factory, std::string>> types_;
};

}  // namespace saw::deploy

// Small server and client components used by the core unit tests.
#pragma once

#include <vector>

#include "saw/manager.hpp"

namespace saw::testing {

struct Vec {
  double x = 0, y = 0, z = 0;
};

// A server offering one of each command and event kind; `threaded` picks Task or Component.
template <class Base>
class Server : public Base {
 public:
  template <class... A>
  explicit Server(A&&... a) : Base(std::forward<A>(a)...) {
    ProvidedInterface& p = this->provide("p");
    p.add_command_void("bump", [this] { executed.push_back(-1); });
    p.add_command_write<int>("push", [this](const int& v) { executed.push_back(v); });
    p.add_command_read("position", this->state_table().add_column("position", &position));
    p.add_command_qualified_read<double, double>("twice", [](const double& q, double& r) { r = 2 * q; });
    ping = &p.add_event_void("ping");
    value = &p.add_event_write<int>("value");
  }
  void run() override { position.x += 1; }
  std::vector<int> executed;
  Vec position;
  EventVoid* ping;
  EventWrite<int>* value;
};

class Client : public Task {
 public:
  explicit Client(std::string name = "client")
      : Task(std::move(name), TaskConfig::periodic(std::chrono::milliseconds(1), 0)) {
    auto& r = require("r");
    r.add_function("bump", bump);
    r.add_function("push", push);
    r.add_function("position", position);
    r.add_function("twice", twice);
    r.add_event_handler_void("ping", [this] { ++pings; });
    r.add_event_handler_write<int>("value", [this](const int& v) { values.push_back(v); });
  }
  FunctionVoid bump;
  FunctionWrite<int> push;
  FunctionRead<Vec> position;
  FunctionQualifiedRead<double, double> twice;
  int pings = 0;
  std::vector<int> values;
};

using TaskServer = Server<Task>;
using PassiveServer = Server<Component>;

inline TaskConfig one_ms() { return TaskConfig::periodic(std::chrono::milliseconds(1), 0); }

}  // namespace saw::testing

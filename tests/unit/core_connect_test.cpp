// Connect errors: each names both components, both interfaces, the command and both types.
#include <gtest/gtest.h>

#include "core_fixtures.hpp"

namespace {

using namespace saw::testing;

// A client whose one function or handler has the given shape.
template <class F>
class Asker : public saw::Task {
 public:
  explicit Asker(const char* command, saw::Need need = saw::Need::required) : Task("asker", one_ms()) {
    require("r").add_function(command, f, need);
  }
  F f;
};

std::string connect_error(saw::Component& client) {
  TaskServer server("server", one_ms());
  saw::Manager m;
  m.add(server);
  m.add(client);
  try {
    m.connect("asker", "r", "server", "p");
  } catch (const saw::ConnectError& e) {
    return e.what();
  }
  return "";
}

void expect_names(const std::string& msg, std::initializer_list<const char*> parts) {
  for (const char* p : parts)
    EXPECT_NE(msg.find(p), std::string::npos) << "missing '" << p << "' in: " << msg;
}

TEST(Connect, TypeMismatchNamesEverything) {
  Asker<saw::FunctionWrite<float>> a("push");
  expect_names(connect_error(a), {"'asker'", "'r'", "'server'", "'p'", "'push'", "write command<float32>",
                                  "write command<int32>"});
}

TEST(Connect, KindMismatch) {
  Asker<saw::FunctionRead<int>> a("push");
  expect_names(connect_error(a), {"'push'", "read command<int32>", "write command<int32>"});
}

TEST(Connect, QualifiedReadResultMismatch) {
  Asker<saw::FunctionQualifiedRead<double, float>> a("twice");
  expect_names(connect_error(a), {"'twice'", "float64 -> float32", "float64 -> float64"});
}

TEST(Connect, EventTypeMismatch) {
  class E : public saw::Task {
   public:
    E() : Task("asker", one_ms()) {
      require("r").add_event_handler_write<double>("value", [](const double&) {});
    }
  } e;
  expect_names(connect_error(e), {"'value'", "write event<float64>", "write event<int32>"});
}

TEST(Connect, MissingRequiredCommandIsAnErrorMissingOptionalIsNot) {
  Asker<saw::FunctionVoid> required("reset");
  expect_names(connect_error(required), {"'reset'", "no such command"});

  TaskServer server("server", one_ms());
  Asker<saw::FunctionVoid> optional("reset", saw::Need::optional);
  saw::Manager m;
  m.add(server);
  m.add(optional);
  EXPECT_NO_THROW(m.connect("asker", "r", "server", "p"));
  m.start_stepped();
  EXPECT_EQ(optional.f(), saw::Status::disconnected);
}

TEST(Connect, UnknownNamesAndRepeatsAndLateConnects) {
  TaskServer server("server", one_ms());
  Client client;
  saw::Manager m;
  m.add(server);
  m.add(client);
  EXPECT_THROW(m.connect("nobody", "r", "server", "p"), saw::ConnectError);
  EXPECT_THROW(m.connect("client", "r", "nobody", "p"), saw::ConnectError);
  try {
    m.connect("client", "x", "server", "p");
    ADD_FAILURE();
  } catch (const saw::ConnectError& e) {
    expect_names(e.what(), {"no required interface 'x'", "it has 'r'"});
  }
  try {
    m.connect("client", "r", "server", "x");
    ADD_FAILURE();
  } catch (const saw::ConnectError& e) {
    expect_names(e.what(), {"no provided interface 'x'", "it has 'task', 'p'"});
  }
  m.connect("client", "r", "server", "p");
  EXPECT_THROW(m.connect("client", "r", "server", "p"), saw::ConnectError) << "already connected";
  m.start_stepped();
  EXPECT_THROW(m.connect("client", "r", "server", "task"), saw::ConnectError) << "after start";
}

TEST(Connect, AFailedConnectChangesNothing) {
  TaskServer server("server", one_ms());
  class Mixed : public saw::Task {
   public:
    Mixed() : Task("asker", one_ms()) {
      auto& r = require("r");
      r.add_function("push", push);
      r.add_function("twice", bad);  // wrong result type
    }
    saw::FunctionWrite<int> push;
    saw::FunctionQualifiedRead<double, int> bad;
  } mixed;
  saw::Manager m;
  m.add(server);
  m.add(mixed);
  EXPECT_THROW(m.connect("asker", "r", "server", "p"), saw::ConnectError);
  EXPECT_FALSE(mixed.push.is_bound());
  EXPECT_FALSE(mixed.required("r")->is_connected());
  EXPECT_EQ(server.value->observer_count(), 0u);
}

TEST(Connect, CheckSaysWhatConnectWouldAndBindsNothing) {
  TaskServer server("server", one_ms());
  Client client;
  Asker<saw::FunctionWrite<float>> wrong("push", saw::Need::optional);  // a wrong type, optional or not
  saw::Manager m;
  m.add(server);
  m.add(client);
  m.add(wrong);

  EXPECT_FALSE(m.check("client", "r", "server", "p").has_value());
  EXPECT_FALSE(client.push.is_bound());
  EXPECT_FALSE(client.required("r")->is_connected());
  EXPECT_EQ(server.value->observer_count(), 0u);

  const auto mismatch = m.check("asker", "r", "server", "p");
  ASSERT_TRUE(mismatch.has_value());
  expect_names(mismatch->what(), {"'asker'", "'r'", "'server'", "'p'", "'push'", "write command<float32>",
                                  "write command<int32>"});
  const auto unknown = m.check("client", "x", "server", "p");
  ASSERT_TRUE(unknown.has_value());
  expect_names(unknown->what(), {"no required interface 'x'"});
  ASSERT_TRUE(m.check("client", "r", "nobody", "p").has_value());

  // The same answer as connect(): this one connects, and then it would be a second connect.
  m.connect("client", "r", "server", "p");
  const auto again = m.check("client", "r", "server", "p");
  ASSERT_TRUE(again.has_value());
  expect_names(again->what(), {"already connected to server.p"});

  m.start_stepped();
  ASSERT_EQ(client.push(7), saw::Status::ok);
  m.step();
  EXPECT_EQ(server.executed, std::vector<int>{7});
  const auto late = m.check("asker", "r", "server", "task");
  ASSERT_TRUE(late.has_value());
  expect_names(late->what(), {"already started"});
}

TEST(Connect, StartRefusesAnUnconnectedRequiredInterface) {
  Client client;
  saw::Manager m;
  m.add(client);
  try {
    m.start_stepped();
    ADD_FAILURE();
  } catch (const saw::ConnectError& e) {
    expect_names(e.what(), {"'client'.'r' is not connected"});
  }
  EXPECT_EQ(client.lifecycle(), saw::Lifecycle::constructed);
}

}  // namespace

#include <gtest/gtest.h>

#include "saw/manager.hpp"

namespace {

class Server : public saw::Task {
 public:
  Server() : Task("server", saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0)) {
    auto& p = provide("p");
    p.add_command_void("reset", [this] { count_ = 0; });
    p.add_command_write<double>("set_gain", [this](const double& g) { gain_ = g; });
    p.add_command_read("count", state_table().add_column("count", &count_));
    p.add_command_qualified_read<double, double>("times_two", [](const double& q, double& r) { r = 2 * q; });
    tick_ = &p.add_event_write<std::int64_t>("tick");
  }
  void run() override {
    ++count_;
    (void)(*tick_)(count_);
  }
  std::int64_t count_ = 0;
  double gain_ = 1;
  saw::EventWrite<std::int64_t>* tick_;
};

class Client : public saw::Task {
 public:
  Client() : Task("client", saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0)) {
    auto& r = require("r");
    r.add_function("reset", reset);
    r.add_function("set_gain", set_gain);
    r.add_function("count", count);
    r.add_function("times_two", times_two);
    r.add_event_handler_write<std::int64_t>("tick", [this](const std::int64_t& v) { last_tick = v; });
  }
  saw::FunctionVoid reset;
  saw::FunctionWrite<double> set_gain;
  saw::FunctionRead<std::int64_t> count;
  saw::FunctionQualifiedRead<double, double> times_two;
  std::int64_t last_tick = 0;
};

TEST(Smoke, SteppedRoundTrip) {
  Server s;
  Client c;
  saw::Manager m;
  m.add(s);
  m.add(c);
  m.connect("client", "r", "server", "p");
  m.start_stepped();
  EXPECT_EQ(c.set_gain(3.0), saw::Status::ok);
  m.step();
  EXPECT_EQ(s.gain_, 3.0);
  std::int64_t v = 0;
  EXPECT_EQ(c.count(v), saw::Status::ok);
  EXPECT_EQ(v, 1);
  double r = 0;
  EXPECT_EQ(c.times_two(4.0, r), saw::Status::ok);
  EXPECT_EQ(r, 8.0);
  m.step();
  // The server runs first (added first): the client drained ticks 1 and 2 this step.
  EXPECT_EQ(c.last_tick, 2);
  m.stop();
}

}  // namespace

// Every command and event kind, queued (server is a task) and direct (server has no thread).
#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>

#include "core_fixtures.hpp"

namespace {

using namespace saw::testing;

struct Pair {
  Pair() : server("server", one_ms()) {
    server.provided("p")->set_mailbox_capacity(4);
    m.add(server);
    m.add(client);
    m.connect("client", "r", "server", "p");
    m.start_stepped();
  }
  TaskServer server;
  Client client;
  saw::Manager m;
};

TEST(Commands, VoidAndWriteRunInTheServersNextCycleInOrder) {
  Pair p;
  ASSERT_EQ(p.client.push(7), saw::Status::ok);
  ASSERT_EQ(p.client.bump(), saw::Status::ok);
  ASSERT_EQ(p.client.push(9), saw::Status::ok);
  EXPECT_TRUE(p.server.executed.empty()) << "queued, not run at call time";
  p.m.step();
  EXPECT_EQ(p.server.executed, (std::vector<int>{7, -1, 9}));
}

TEST(Commands, ReadServesTheNewestRowWithItsStampAndHistory) {
  Pair p;
  Vec v;
  EXPECT_EQ(p.client.position(v), saw::Status::no_data);
  for (int i = 0; i < 5; ++i) p.m.step();  // rows at t = 0..4 ms, x = 1..5
  saw::RowStamp stamp;
  ASSERT_EQ(p.client.position(v, stamp), saw::Status::ok);
  EXPECT_EQ(v.x, 5);
  EXPECT_EQ(stamp.tick, 4u);
  EXPECT_EQ(stamp.time, 4'000'000);
  ASSERT_EQ(p.client.position.at_or_before(2'500'000, v), saw::Status::ok);
  EXPECT_EQ(v.x, 3);
}

TEST(Commands, QualifiedReadRunsInTheCallersThread) {
  Pair p;
  double r = 0;
  ASSERT_EQ(p.client.twice(21.0, r), saw::Status::ok);  // no step needed
  EXPECT_EQ(r, 42.0);
}

TEST(Commands, FullMailboxIsAnErrorCountedAndLosesNothingAccepted) {
  Pair p;
  int accepted = 0, refused = 0;
  for (int i = 0; i < 10; ++i) (p.client.push(i) == saw::Status::ok ? accepted : refused)++;
  EXPECT_EQ(accepted, 4);
  EXPECT_EQ(refused, 6);
  p.m.step();
  EXPECT_EQ(p.server.executed, (std::vector<int>{0, 1, 2, 3}));
  ASSERT_EQ(p.client.push(99), saw::Status::ok) << "space again after the server's cycle";
  p.m.step();
  EXPECT_EQ(p.server.executed.back(), 99);
}

TEST(Events, DeliveredInEachObserversNextCycle) {
  TaskServer server("server", one_ms());
  Client a("a"), b("b");
  saw::Manager m;
  m.add(server);
  m.add(a);
  m.add(b);
  m.connect("a", "r", "server", "p");
  m.connect("b", "r", "server", "p");
  m.start_stepped();
  EXPECT_EQ((*server.ping)(), saw::Status::ok);
  EXPECT_EQ((*server.value)(5), saw::Status::ok);
  EXPECT_EQ(a.pings, 0) << "queued for the observer's thread";
  m.step();
  EXPECT_EQ(a.pings, 1);
  EXPECT_EQ(b.pings, 1);
  EXPECT_EQ(a.values, std::vector<int>{5});
  EXPECT_EQ(b.values, std::vector<int>{5});
}

TEST(Events, FullObserverMailboxIsCounted) {
  TaskServer server("server", one_ms());
  Client a("a");
  a.required("r")->set_event_capacity(2);
  saw::Manager m;
  m.add(server);
  m.add(a);
  m.connect("a", "r", "server", "p");
  m.start_stepped();
  for (int i = 0; i < 5; ++i) (void)(*server.value)(i);
  EXPECT_EQ(server.value->dropped(), 3u);
  EXPECT_EQ((*server.value)(9), saw::Status::queue_full);
  m.step();
  EXPECT_EQ(a.values, (std::vector<int>{0, 1}));
}

TEST(PassiveServer, CommandsRunInTheCallersThreadAtOnce) {
  PassiveServer server("server");
  Client c;
  saw::Manager m;
  m.add(server);
  m.add(c);
  m.connect("client", "r", "server", "p");
  m.start_stepped();
  ASSERT_EQ(c.push(3), saw::Status::ok);
  EXPECT_EQ(server.executed, std::vector<int>{3});
  double r = 0;
  ASSERT_EQ(c.twice(1.5, r), saw::Status::ok);
  EXPECT_EQ(r, 3.0);
}

TEST(Interfaces, ACommandAndAnEventMayShareANameTwoCommandsMayNot) {
  saw::Component c("c");
  auto& p = c.provide("p");
  p.add_command_void("state", [] {});
  EXPECT_NO_THROW(p.add_event_void("state"));
  EXPECT_THROW(p.add_command_write<int>("state", [](const int&) {}), std::invalid_argument);
  EXPECT_THROW(p.add_event_write<int>("state"), std::invalid_argument);
}

}  // namespace

namespace {

TEST(Commands, LimitsAreDeclaredOnWriteCommandsOnlyWithFiniteOrderedBounds) {
  saw::testing::TaskServer server("server", saw::testing::one_ms());
  auto& p = *server.provided("p");
  EXPECT_FALSE(p.find_command("push")->limits.has_value());
  p.limit("push", -3, 5);
  ASSERT_TRUE(p.find_command("push")->limits.has_value());
  EXPECT_EQ(p.find_command("push")->limits->min, -3);
  EXPECT_EQ(p.find_command("push")->limits->max, 5);
  EXPECT_THROW(p.limit("position", 0, 1), std::invalid_argument);  // a read command
  EXPECT_THROW(p.limit("nothing", 0, 1), std::invalid_argument);
  EXPECT_THROW(p.limit("push", 2, 1), std::invalid_argument);
  EXPECT_THROW(p.limit("push", 0, std::numeric_limits<double>::infinity()), std::invalid_argument);
}

}  // namespace

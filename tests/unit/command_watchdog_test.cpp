#include "saw/command_watchdog.hpp"

#include <gtest/gtest.h>

namespace {

// The deadline: a device whose commands stop drops its output once, says so in its columns, and
// watches again from the next command.
TEST(CommandWatchdog, TripsOnceWhenCommandsStopAndRearmsOnTheNext) {
  saw::StateTable table(16);
  saw::CommandWatchdog w(table);
  table.finalize();
  w.set_timeout(3);
  EXPECT_FALSE(w.expired(100)) << "nothing to watch before a first command";
  w.commanded(10);
  EXPECT_FALSE(w.expired(13)) << "exactly the timeout old is still fresh";
  EXPECT_TRUE(w.expired(14));
  EXPECT_TRUE(w.holding());
  EXPECT_FALSE(w.expired(15)) << "once";
  EXPECT_EQ(w.trips(), 1u);
  EXPECT_EQ(w.last_command(), 10);
  table.advance(15);
  bool holding = false;
  std::uint64_t trips = 0;
  ASSERT_EQ(table.read_latest(w.holding_column(), holding), saw::Status::ok);
  ASSERT_EQ(table.read_latest(w.trips_column(), trips), saw::Status::ok);
  EXPECT_TRUE(holding);
  EXPECT_EQ(trips, 1u);
  w.commanded(20);
  EXPECT_FALSE(w.holding());
  w.disarm();  // a fault dropped the output: no trip counted for it
  EXPECT_FALSE(w.expired(100));
  EXPECT_EQ(w.trips(), 1u);
}

}  // namespace

// FaultInfo: a fault any component can raise, checked when it comes from another process.
#include "saw/fault.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "saw/value_check.hpp"

namespace {

TEST(FaultInfo, ADevicesFaultSaysWhichDeviceAndItsOwnCode) {
  saw::FaultInfo f;
  f.code = saw::FaultCode::device_lost;
  f.set_source("usb 1-2");
  f.last_read = saw::Status::timeout;
  f.since_start_ns = 2'500'000'000;
  EXPECT_EQ(saw::to_string(f), "usb 1-2 device lost (last read: timeout), at t=2.500 s");
  EXPECT_EQ(saw::to_string(saw::FaultInfo{}), "no fault");
}

TEST(FaultInfo, ASourceIsBoundedAndBytesFromAnotherProcessAreChecked) {
  saw::FaultInfo f;
  f.set_source(std::string(100, 's'));
  EXPECT_EQ(f.source_name().size(), saw::FaultInfo::max_source) << "a label, cut to its field";
  EXPECT_TRUE(saw::check_value(f));

  saw::FaultInfo bad = f;
  std::memset(bad.source.data(), 's', bad.source.size());  // no NUL inside the field
  EXPECT_FALSE(saw::check_value(bad));
  bad = f;
  std::memset(&bad.code, 200, 1);  // not a FaultCode
  EXPECT_FALSE(saw::check_value(bad));
  bad = f;
  std::memset(&bad.last_read, 99, 1);  // not a Status
  EXPECT_FALSE(saw::check_value(bad));
}

}  // namespace

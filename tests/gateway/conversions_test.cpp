// The conversions of what a dVRK sends that are not plain numbers: its console's buttons.
#include <gtest/gtest.h>

#include "crtk_conversions.hpp"

namespace {

using saw::gateway::conversions::ButtonConv;

saw::ButtonEvent from(int value, bool& ok, std::string& why) {
  sensor_msgs::msg::Joy m;
  m.buttons({value});
  saw::ButtonEvent b{};
  ok = ButtonConv::from_msg(m, b, why);
  return b;
}

// The dVRK's console sends [1] pressed, [0] released and [2] for a quick tap (cisst-ros CLICKED).
TEST(ButtonConversion, AQuickTapIsNeitherAPressNorARelease) {
  bool ok = false;
  std::string why;
  EXPECT_TRUE(from(1, ok, why).pressed);
  EXPECT_TRUE(ok);
  EXPECT_FALSE(from(0, ok, why).pressed);
  EXPECT_TRUE(ok);
  (void)from(2, ok, why);
  EXPECT_FALSE(ok) << "a tap taken as a press would leave the clutch held";
  EXPECT_NE(why.find("quick tap"), std::string::npos) << why;
  (void)from(-1, ok, why);
  EXPECT_FALSE(ok);
  sensor_msgs::msg::Joy none;
  saw::ButtonEvent b{};
  EXPECT_FALSE(ButtonConv::from_msg(none, b, why)) << "no button at all";
}

}  // namespace

#include <gtest/gtest.h>

#include "oit_rop/SystemcInfo.hpp"

// The build must pick up Debian's SystemC 2.3.4 through pkg-config, compiled
// with the C++17 API version symbol although the product is C++20.
TEST(SystemcLink, ReleaseIs234) {
  const std::string release = oit::rop::systemcRelease();
  EXPECT_EQ(release.rfind("2.3.4", 0), 0u) << release;
}

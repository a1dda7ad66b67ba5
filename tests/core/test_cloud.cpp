#include <gtest/gtest.h>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse {
namespace {

TEST(Bounds, EmptyIsZero) {
  Bounds b = bounds({});
  EXPECT_TRUE(b.min.isZero());
  EXPECT_TRUE(b.max.isZero());
}

TEST(Bounds, CoversEveryPoint) {
  Bounds b = bounds({Vec3(1, -2, 3), Vec3(-1, 4, 0), Vec3(0, 0, 5)});
  EXPECT_EQ(b.min, Vec3(-1, -2, 0));
  EXPECT_EQ(b.max, Vec3(1, 4, 5));
  EXPECT_EQ(b.extent(), Vec3(2, 6, 5));
}

TEST(Expected, HoldsValueOrError) {
  Expected<int> good = 3;
  ASSERT_TRUE(good.ok());
  EXPECT_EQ(*good, 3);
  Expected<int> bad = invalid_argument("no points");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::kInvalidArgument);
  EXPECT_EQ(bad.error().message, "no points");
  EXPECT_STREQ(to_string(bad.error().code), "invalid argument");
}

}  // namespace
}  // namespace glimpse

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "client/scan.h"

namespace glimpse::client {
namespace {

Cloud RandomCloud(size_t n, uint64_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Cloud c;
  for (size_t i = 0; i < n; ++i) c.points.push_back(Vec3(u(rng), u(rng), u(rng) + 1.0f));
  return c;
}

bool IsPermutation(std::vector<uint32_t> order, size_t n) {
  std::sort(order.begin(), order.end());
  std::vector<uint32_t> expected(n);
  std::iota(expected.begin(), expected.end(), 0u);
  return order == expected;
}

TEST(ParseRevealOrder, KnowsTheThreeOrders) {
  EXPECT_EQ(*ParseRevealOrder("top-down"), RevealOrder::kTopDown);
  EXPECT_EQ(*ParseRevealOrder("random"), RevealOrder::kRandom);
  EXPECT_EQ(*ParseRevealOrder("sweep"), RevealOrder::kSweep);
  EXPECT_FALSE(ParseRevealOrder("bottom-up").ok());
}

TEST(RevealSequence, EmptyViewGivesEmptyOrder) {
  for (RevealOrder o : {RevealOrder::kTopDown, RevealOrder::kRandom, RevealOrder::kSweep})
    EXPECT_TRUE(RevealSequence(Cloud{}, o, 1).empty());
}

TEST(RevealSequence, TopDownIsDescendingZ) {
  const Cloud c = RandomCloud(500, 3);
  const auto order = RevealSequence(c, RevealOrder::kTopDown, 0);
  ASSERT_TRUE(IsPermutation(order, c.points.size()));
  for (size_t i = 1; i < order.size(); ++i) EXPECT_GE(c.points[order[i - 1]].z(), c.points[order[i]].z());
}

TEST(RevealSequence, RandomIsASeededPermutation) {
  const Cloud c = RandomCloud(300, 4);
  const auto a = RevealSequence(c, RevealOrder::kRandom, 7);
  EXPECT_TRUE(IsPermutation(a, c.points.size()));
  EXPECT_EQ(a, RevealSequence(c, RevealOrder::kRandom, 7));
  EXPECT_NE(a, RevealSequence(c, RevealOrder::kRandom, 8));
}

TEST(RevealSequence, SweepRunsLeftToRightAsTheSensorSeesIt) {
  Cloud c = RandomCloud(400, 5);
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : c.points) centroid += p;
  centroid /= float(c.points.size());
  c.sensor = centroid + Vec3(0, -5, 0);  // looking along +y with +z up: the image's right is +x
  auto order = RevealSequence(c, RevealOrder::kSweep, 0);
  ASSERT_TRUE(IsPermutation(order, c.points.size()));
  for (size_t i = 1; i < order.size(); ++i) EXPECT_LE(c.points[order[i - 1]].x(), c.points[order[i]].x());
  c.sensor = centroid + Vec3(5, 0, 0);  // looking along -x: the image's right is +y
  order = RevealSequence(c, RevealOrder::kSweep, 0);
  for (size_t i = 1; i < order.size(); ++i) EXPECT_LE(c.points[order[i - 1]].y(), c.points[order[i]].y());
}

TEST(RevealSequence, SweepWithoutSensorRunsAlongX) {
  const Cloud c = RandomCloud(100, 6);
  const auto order = RevealSequence(c, RevealOrder::kSweep, 0);
  for (size_t i = 1; i < order.size(); ++i) EXPECT_LE(c.points[order[i - 1]].x(), c.points[order[i]].x());
}

TEST(Reordered, KeepsSensorAndFollowsOrder) {
  Cloud c;
  c.points = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)};
  c.sensor = Vec3(0, 0, 9);
  const Cloud r = Reordered(c, {2, 0, 1});
  EXPECT_EQ(r.points[0].x(), 2.0f);
  EXPECT_EQ(r.points[2].x(), 1.0f);
  EXPECT_EQ(r.sensor, c.sensor);
}

TEST(ChunkEnds, ByCountIsNearlyEqualAndEndsAtTheLastPoint) {
  EXPECT_TRUE(ChunkEnds(0, 5, 0).empty());
  EXPECT_EQ(ChunkEnds(10, 3, 0), (std::vector<size_t>{3, 6, 10}));
  EXPECT_EQ(ChunkEnds(10, 1, 0), (std::vector<size_t>{10}));
  EXPECT_EQ(ChunkEnds(3, 10, 0), (std::vector<size_t>{1, 2, 3}));  // at most one chunk per point
  const auto ends = ChunkEnds(1001, 20, 0);
  ASSERT_EQ(ends.size(), 20u);
  EXPECT_EQ(ends.back(), 1001u);
  for (size_t i = 1; i < ends.size(); ++i) EXPECT_NEAR(double(ends[i] - ends[i - 1]), 50.05, 1.0);
}

TEST(ChunkEnds, ByPointsLeavesAShorterLastChunk) {
  EXPECT_EQ(ChunkEnds(10, 0, 4), (std::vector<size_t>{4, 8, 10}));
  EXPECT_EQ(ChunkEnds(8, 0, 4), (std::vector<size_t>{4, 8}));
  EXPECT_EQ(ChunkEnds(3, 0, 100), (std::vector<size_t>{3}));
  EXPECT_TRUE(ChunkEnds(0, 0, 4).empty());
}

}  // namespace
}  // namespace glimpse::client

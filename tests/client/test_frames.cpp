// glimpse stream --frames: a folder of frames, each with its sensor, in natural name order; poses.csv
// places frames whose points are in the sensor's own frame; every bad input names the file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "client/frames.h"
#include "common/temp_dir.h"
#include "glimpse/io/files.h"

namespace glimpse::client {
namespace {

namespace fs = std::filesystem;

class FramesTest : public ::testing::Test {
 protected:
  void Write(const std::string& name, Cloud c) { ASSERT_TRUE(write_cloud((dir_ / name).string(), c).ok()); }
  void Text(const std::string& name, const std::string& text) { std::ofstream(dir_ / name) << text; }
  glimpse::testing::TempDir tmp_{"client-frames"};
  fs::path dir_ = tmp_.path();
};

Cloud Points(std::initializer_list<Vec3> p, std::optional<Vec3> sensor) {
  Cloud c;
  c.points = p;
  c.sensor = sensor;
  return c;
}

TEST(NaturalLess, NumbersCompareAsNumbers) {
  EXPECT_TRUE(NaturalLess("frame2.pcd", "frame10.pcd"));
  EXPECT_FALSE(NaturalLess("frame10.pcd", "frame2.pcd"));
  EXPECT_TRUE(NaturalLess("view_60.pcd", "view_120.pcd"));
  EXPECT_TRUE(NaturalLess("a.pcd", "b.pcd"));
  EXPECT_TRUE(NaturalLess("f1.pcd", "f1a.pcd"));
  EXPECT_NE(NaturalLess("f01.pcd", "f1.pcd"), NaturalLess("f1.pcd", "f01.pcd"));  // strict: one order
  EXPECT_FALSE(NaturalLess("x", "x"));
}

TEST_F(FramesTest, FramesComeInNaturalOrderWithTheirOwnSensors) {
  Write("frame10.pcd", Points({{1, 0, 0}}, Vec3(0, 0, 10)));
  Write("frame2.ply", Points({{2, 0, 0}, {3, 0, 0}}, Vec3(0, 0, 2)));
  Write("frame1.xyz", Points({{4, 0, 0}}, Vec3(0, 0, 1)));
  Text("notes.md", "not a frame");
  Text(".hidden.pcd", "skipped");
  auto frames = LoadFrames(dir_.string());
  ASSERT_TRUE(frames.ok()) << frames.error().message;
  ASSERT_EQ(frames->size(), 3u);
  EXPECT_EQ(*(*frames)[0].sensor, Vec3(0, 0, 1));
  EXPECT_EQ(*(*frames)[1].sensor, Vec3(0, 0, 2));
  EXPECT_EQ(*(*frames)[2].sensor, Vec3(0, 0, 10));
  EXPECT_EQ((*frames)[1].points.size(), 2u);
  // Cut into chunks of at most 1 point, each chunk keeps its frame's sensor.
  const std::vector<Cloud> chunks = FrameChunks(*frames, 1);
  ASSERT_EQ(chunks.size(), 4u);
  EXPECT_EQ(*chunks[1].sensor, Vec3(0, 0, 2));
  EXPECT_EQ(*chunks[2].sensor, Vec3(0, 0, 2));
  EXPECT_EQ(chunks[2].points[0], Vec3(3, 0, 0));
  EXPECT_EQ(FrameChunks(*frames, 0).size(), 3u);
}

TEST_F(FramesTest, PosesPlaceFramesTakenInTheSensorsOwnFrame) {
  Write("a.xyz", Points({{1, 0, 0}, {0, 1, 0}}, std::nullopt));  // sensor frame: rotated and moved
  Write("b.xyz", Points({{5, 5, 5}}, std::nullopt));              // common frame: sensor only
  // a: 90 degrees about +z (qw = qz = sqrt(1/2)), the sensor at (10, 0, 1).
  const double h = std::sqrt(0.5);
  Text("poses.csv", "file,x,y,z,qw,qx,qy,qz\na.xyz,10,0,1," + std::to_string(h) + ",0,0," + std::to_string(h) +
                        "\nb.xyz,0,-3,1\n");
  auto frames = LoadFrames(dir_.string());
  ASSERT_TRUE(frames.ok()) << frames.error().message;
  ASSERT_EQ(frames->size(), 2u);
  EXPECT_EQ(*(*frames)[0].sensor, Vec3(10, 0, 1));
  EXPECT_TRUE((*frames)[0].points[0].isApprox(Vec3(10, 1, 1), 1e-5f)) << (*frames)[0].points[0].transpose();
  EXPECT_TRUE((*frames)[0].points[1].isApprox(Vec3(9, 0, 1), 1e-5f)) << (*frames)[0].points[1].transpose();
  EXPECT_EQ(*(*frames)[1].sensor, Vec3(0, -3, 1));
  EXPECT_EQ((*frames)[1].points[0], Vec3(5, 5, 5));
}

TEST_F(FramesTest, EveryBadInputNamesTheFile) {
  auto expect_error = [&](const std::string& needle) {
    auto frames = LoadFrames(dir_.string());
    ASSERT_FALSE(frames.ok()) << "expected an error with '" << needle << "'";
    EXPECT_NE(frames.error().message.find(needle), std::string::npos) << needle << " in: " << frames.error().message;
  };
  expect_error("no frame");
  Write("f1.xyz", Points({{1, 0, 0}}, std::nullopt));
  expect_error("f1.xyz: a frame needs its sensor position");
  Text("poses.csv", "f1.xyz,0,0\n");
  expect_error("poses.csv:1: expected file,x,y,z");
  Text("poses.csv", "f1.xyz,0,0,nan\n");
  expect_error("poses.csv:1: 'nan' is not a finite number");
  Text("poses.csv", "f1.xyz,0,0,1,1,1,0,0\n");
  expect_error("poses.csv:1: the quaternion qw,qx,qy,qz must be a unit one");
  // A header naming the quaternion x,y,z,w: read w first it would turn every frame the wrong way.
  Text("poses.csv", "file,x,y,z,qx,qy,qz,qw\nf1.xyz,3,0,1,0,0,0.707106781,0.707106781\n");
  expect_error("poses.csv:1: the header must be file,x,y,z or file,x,y,z,qw,qx,qy,qz (w first)");
  Text("poses.csv", "f1.xyz,0,0,1\nf9.xyz,0,0,1\n");
  expect_error("'f9.xyz' is not a frame of the folder");
  Text("poses.csv", "f1.xyz,0,0,1\nf1.xyz,0,0,2\n");
  expect_error("poses.csv:2: 'f1.xyz' is listed twice");
  fs::remove(dir_ / "poses.csv");
  Write("f1.xyz", Points({{1, 0, 0}}, Vec3(0, 0, 1)));
  Text("f2.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expect_error("f2.off: a frame is a point cloud, not a mesh");
  EXPECT_FALSE(LoadFrames((dir_ / "missing").string()).ok());
}

}  // namespace
}  // namespace glimpse::client

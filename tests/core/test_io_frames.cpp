// PCD frames as depth cameras' grabbers save them: DATA binary_compressed (LZF, read through PCL's
// reader), organised with NaN where the camera saw nothing, and the real Kinect-class frames beside the
// repository.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "common/temp_dir.h"
#include "io_files.h"
#include "glimpse/io/files.h"

namespace glimpse {
namespace {

namespace fs = std::filesystem;


using test::IoTest;
using test::put;

// ---- binary_compressed (LZF; PCL's default for grabbed frames) ----

// LZF as PCL's reader takes it: literal runs of at most 32 bytes, and a repeated byte as back references
// to the byte before it (distance 1), so that a column of equal values compresses as a camera's do.
std::string lzf(const std::string& in) {
  std::string out, literal;
  auto flush = [&] {
    for (size_t i = 0; i < literal.size(); i += 32) {
      const std::string part = literal.substr(i, 32);
      out += char(part.size() - 1);
      out += part;
    }
    literal.clear();
  };
  for (size_t i = 0; i < in.size();) {
    size_t run = 0;
    while (i > 0 && i + run < in.size() && run < 264 && in[i + run] == in[i - 1]) ++run;
    if (run < 3) {
      literal += in[i++];
      continue;
    }
    flush();
    const size_t len = run - 2;  // the code's length: 2 bytes fewer than it copies
    out += char(std::min<size_t>(len, 7) << 5);
    if (len >= 7) out += char(len - 7);
    out += char(0);  // distance 1: the byte before
    i += run;
  }
  flush();
  return out;
}

// A frame as PCL's grabbers write one: FIELDS x y z rgba, organised `width` wide, NaN where the camera
// saw nothing; DATA binary (one record per point) or binary_compressed (each field's values together,
// LZF, after their compressed and uncompressed sizes).
std::string organised_pcd(const Points& points, size_t width, bool compressed, const std::string& comments = "") {
  const std::string n = std::to_string(points.size());
  std::string s = "# .PCD v0.7 - Point Cloud Data file format\n" + comments + "VERSION 0.7\nFIELDS x y z rgba\n" +
                  "SIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH " + std::to_string(width) + "\nHEIGHT " +
                  std::to_string(points.size() / width) + "\nVIEWPOINT 0.5 0 1 1 0 0 0\nPOINTS " + n + "\nDATA " +
                  (compressed ? "binary_compressed\n" : "binary\n");
  auto rgba = [](const Vec3& p, size_t i) { return p.allFinite() ? uint32_t(0xff203040u + i) : 0u; };
  if (!compressed) {
    for (size_t i = 0; i < points.size(); ++i) {
      for (int a = 0; a < 3; ++a) put(s, points[i][a], false);
      put(s, rgba(points[i], i), false);
    }
    return s;
  }
  std::string columns;
  for (int a = 0; a < 3; ++a)
    for (const Vec3& p : points) put(columns, p[a], false);
  for (size_t i = 0; i < points.size(); ++i) put(columns, rgba(points[i], i), false);
  const std::string body = lzf(columns);
  put(s, uint32_t(body.size()), false);
  put(s, uint32_t(columns.size()), false);
  return s + body;
}

// 16 x 12 pixels of a wall 2 m away, a third of them (whole runs, as at an object's edge) missing.
Points camera_frame() {
  Points points;
  for (int row = 0; row < 12; ++row)
    for (int col = 0; col < 16; ++col) {
      const bool missing = (row * 16 + col) % 9 < 3;
      points.push_back(missing ? Vec3::Constant(std::numeric_limits<float>::quiet_NaN())
                               : Vec3(0.01f * float(col) - 0.08f, 0.01f * float(row) - 0.06f, 2.f + 0.001f * float(col * row)));
    }
  return points;
}

TEST_F(IoTest, PcdBinaryCompressedReadsAsTheBinaryPath) {
  const Points frame = camera_frame();
  const std::string comments = "# glimpse_frame 0 0 1 0 -1 0 57 43\n";
  const std::string compressed_bytes = organised_pcd(frame, 16, true, comments);
  ASSERT_LT(compressed_bytes.size(), organised_pcd(frame, 16, false, comments).size());  // the runs did compress
  Expected<Cloud> binary = read_cloud(write("binary.pcd", organised_pcd(frame, 16, false, comments)));
  Expected<Cloud> compressed = read_cloud(write("compressed.pcd", compressed_bytes));
  ASSERT_TRUE(binary.ok()) << binary.error().message;
  ASSERT_TRUE(compressed.ok()) << compressed.error().message;
  ASSERT_EQ(compressed->points.size(), frame.size());  // organised: every pixel, in order
  ASSERT_EQ(binary->points.size(), frame.size());
  size_t missing = 0;
  for (size_t i = 0; i < frame.size(); ++i) {
    SCOPED_TRACE(i);
    if (!frame[i].allFinite()) {
      ++missing;
      EXPECT_TRUE(compressed->points[i].array().isNaN().all());  // kept, as the binary path keeps it
      EXPECT_TRUE(binary->points[i].array().isNaN().all());
      continue;
    }
    EXPECT_EQ(compressed->points[i], frame[i]);
    EXPECT_EQ(binary->points[i], frame[i]);
  }
  EXPECT_EQ(missing, 66u);
  // The header as the other paths read it: the VIEWPOINT's translation, the comments' camera frame.
  ASSERT_TRUE(compressed->sensor.has_value());
  EXPECT_EQ(*compressed->sensor, Vec3(0.5f, 0, 1));
  ASSERT_TRUE(compressed->frame.has_value() && binary->frame.has_value());
  EXPECT_TRUE(*compressed->frame == *binary->frame);
  EXPECT_EQ(compressed->frame->fov_h_deg, 57.f);
  Expected<Cloud> view = read_camera_view(path("compressed.pcd"), 57, 43);
  ASSERT_TRUE(view.ok()) << view.error().message;
  EXPECT_EQ(view->points.size(), frame.size());
}

// PCL's OpenNI grabbers write VIEWPOINT 0 0 0 0 1 0 0 (for their viewer) over points in the camera's
// coordinates, z forward: read as the camera pose, the camera would look away from every point.
TEST_F(IoTest, AnOpenNiGrabbersViewpointIsTheCamerasOwnCoordinates) {
  const std::string header = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\n";
  const std::string p = write("openni.pcd", header + "VIEWPOINT 0 0 0 0 1 0 0\nPOINTS 1\nDATA ascii\n0 0 2\n");
  Expected<Cloud> view = read_camera_view(p, 57, 43);
  ASSERT_TRUE(view.ok()) << view.error().message;
  EXPECT_EQ(*view->sensor, Vec3::Zero());
  EXPECT_TRUE(view->frame->axis.isApprox(Vec3::UnitZ())) << view->frame->axis.transpose();
  EXPECT_TRUE(view->frame->up.isApprox(-Vec3::UnitY())) << view->frame->up.transpose();
  // The same half turn elsewhere than at the origin is a pose like any other.
  const std::string moved = write("moved.pcd", header + "VIEWPOINT 0 0 1 0 1 0 0\nPOINTS 1\nDATA ascii\n0 0 2\n");
  view = read_camera_view(moved, 57, 43);
  ASSERT_TRUE(view.ok()) << view.error().message;
  EXPECT_TRUE(view->frame->axis.isApprox(-Vec3::UnitZ())) << view->frame->axis.transpose();
}

TEST_F(IoTest, PcdBinaryCompressedTruncatedOrCorruptIsDataLoss) {
  const std::string good = organised_pcd(camera_frame(), 16, true);
  const size_t body = good.find("DATA binary_compressed\n") + 23;  // the compressed size, then the original's
  std::string bad_size = good, bad_code = good;
  bad_size[body + 4] ^= 0x10;  // an uncompressed size other than POINTS x 16 bytes
  bad_code[body + 8] = char(0xff);  // a back reference to before the first byte
  struct Case {
    std::string name, bytes, where;
  };
  const std::vector<Case> cases = {
      {"cut.pcd", good.substr(0, good.size() - 7), "truncated"},
      {"sizes.pcd", good.substr(0, body + 5), "truncated"},
      {"size.pcd", bad_size, "unpacks to"},
      {"code.pcd", bad_code, "corrupt"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string p = write(c.name, c.bytes);
    ::testing::internal::CaptureStderr();
    Expected<Cloud> cloud = read_cloud(p);
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");  // PCL's complaints stay out of our log
    ASSERT_FALSE(cloud.ok());
    EXPECT_EQ(cloud.error().code, ErrorCode::kDataLoss);
    EXPECT_EQ(cloud.error().message.rfind(p + ":", 0), 0u) << cloud.error().message;
    EXPECT_NE(cloud.error().message.find(c.where), std::string::npos) << cloud.error().message;
  }
  EXPECT_TRUE(read_cloud(write("good.pcd", good)).ok());
}

// ---- real frames (../shared/data/real-scenes, PCL's test data: never copied into the repository) ----

std::string real_scenes_dir() {
  if (const char* env = std::getenv("GLIMPSE_REAL_SCENES_DIR")) return env;
  return GLIMPSE_SOURCE_DIR "/../shared/data/real-scenes";
}

// Four 640 x 480 Kinect-class frames, x y z rgba, binary_compressed; the counts of points with depth are
// what PCL's own loadPCDFile gives.
TEST(RealFrames, ReadEveryPixelAndTheValidPointsPclReads) {
  const std::string dir = real_scenes_dir();
  if (!fs::is_directory(dir)) GTEST_SKIP() << "real scenes not found at " << dir << " (set GLIMPSE_REAL_SCENES_DIR)";
  const std::vector<std::pair<std::string, size_t>> frames = {{"desk_laptop_box_frame0.pcd", 271575},
                                                              {"desk_laptop_box_frame1.pcd", 271395},
                                                              {"desk_laptop_box_frame2.pcd", 271328},
                                                              {"tabletop_milk_bleach_detergent.pcd", 241407}};
  for (const auto& [name, valid] : frames) {
    SCOPED_TRACE(name);
    Expected<Cloud> cloud = read_cloud(dir + "/" + name);
    ASSERT_TRUE(cloud.ok()) << cloud.error().message;
    ASSERT_EQ(cloud->points.size(), 640u * 480u);
    size_t finite = 0, all_nan = 0, in_front = 0;
    for (const Vec3& p : cloud->points) {
      finite += p.allFinite(), all_nan += p.array().isNaN().all();
      in_front += p.z() > 0.2f && p.norm() < 10.f;  // metres, z forward: what a Kinect sees
    }
    EXPECT_EQ(finite, valid);
    EXPECT_EQ(finite + all_nan, cloud->points.size());  // a pixel has depth or none at all
    EXPECT_EQ(in_front, finite);
  }
}

}  // namespace
}  // namespace glimpse

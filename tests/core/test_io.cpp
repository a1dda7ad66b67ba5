#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <limits>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "common/temp_dir.h"
#include "io_files.h"
#include "glimpse/io/files.h"

namespace glimpse {
namespace {

namespace fs = std::filesystem;


Cloud random_cloud(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  Cloud c;
  for (size_t i = 0; i < n; ++i) {
    Vec3 p;
    for (int a = 0; a < 3; ++a) p[a] = float(double(rng() >> 11) * 0x1.0p-53 * 20.0 - 10.0);
    c.points.push_back(p);
  }
  c.points.push_back(Vec3(1e-30f, -3.4e38f, 0.1f));  // extremes survive the text formats
  return c;
}

using test::IoTest;
using test::put;

// ---- round trips ----

TEST_F(IoTest, CloudRoundTripEveryWriterFormat) {
  Cloud cloud = random_cloud(500, 7);
  cloud.sensor = Vec3(0.5f, -2.25f, 3.0f);
  for (const char* ext : {".pcd", ".ply", ".xyz"}) {
    SCOPED_TRACE(ext);
    const std::string p = path(std::string("cloud") + ext);
    ASSERT_TRUE(write_cloud(p, cloud).ok());
    Expected<Cloud> back = read_cloud(p);
    ASSERT_TRUE(back.ok()) << back.error().message;
    ASSERT_EQ(back->points.size(), cloud.points.size());
    for (size_t i = 0; i < cloud.points.size(); ++i) EXPECT_EQ(back->points[i], cloud.points[i]) << i;
    ASSERT_TRUE(back->sensor.has_value());
    EXPECT_EQ(*back->sensor, *cloud.sensor);
  }
}

TEST_F(IoTest, ASensorAtTheOriginRoundTripsInEveryFormat) {
  Cloud cloud = random_cloud(50, 8);
  cloud.sensor = Vec3::Zero();  // a camera-frame scan: not "no sensor", although PCD's VIEWPOINT says identity
  for (const char* ext : {".pcd", ".ply", ".xyz"}) {
    SCOPED_TRACE(ext);
    const std::string p = path(std::string("origin") + ext);
    ASSERT_TRUE(write_cloud(p, cloud).ok());
    Expected<Cloud> back = read_cloud(p);
    ASSERT_TRUE(back.ok()) << back.error().message;
    ASSERT_TRUE(back->sensor.has_value());
    EXPECT_EQ(*back->sensor, Vec3::Zero());
  }
}

TEST_F(IoTest, ACamerasFrameRoundTripsInEveryFormat) {
  Cloud cloud = random_cloud(50, 9);
  cloud.sensor = Vec3(0.1f, -2.f, 1.2f);
  cloud.frame = CameraFrame{Vec3(0.1f, 0.99f, -0.3f), Vec3(0.f, 0.3f, 0.95f), 57.f, 43.5f};
  for (const char* ext : {".pcd", ".ply", ".xyz"}) {
    SCOPED_TRACE(ext);
    const std::string p = path(std::string("frame") + ext);
    ASSERT_TRUE(write_cloud(p, cloud).ok());
    Expected<Cloud> back = read_cloud(p);
    ASSERT_TRUE(back.ok()) << back.error().message;
    ASSERT_TRUE(back->frame.has_value());
    EXPECT_TRUE(*back->frame == *cloud.frame);
  }
}

// PCL's grabbers write a frame in the camera's coordinates (the default VIEWPOINT): the camera at the
// origin looking along +z, the image's up along -y; a VIEWPOINT's rotation turns both.
TEST_F(IoTest, ACameraViewTakesItsPoseFromTheViewpointAndItsFieldOfViewFromTheCaller) {
  const std::string header = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\n";
  const std::string kinect = write("kinect.pcd", header + "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n0 0 2\n");
  Expected<Cloud> view = read_camera_view(kinect, 57, 43);
  ASSERT_TRUE(view.ok()) << view.error().message;
  ASSERT_TRUE(view->sensor && view->frame);
  EXPECT_EQ(*view->sensor, Vec3::Zero());
  EXPECT_TRUE(view->frame->axis.isApprox(Vec3::UnitZ()));
  EXPECT_TRUE(view->frame->up.isApprox(-Vec3::UnitY()));
  EXPECT_EQ(view->frame->fov_h_deg, 57.f);
  EXPECT_EQ(view->frame->fov_v_deg, 43.f);
  EXPECT_FALSE(read_cloud(kinect)->sensor.has_value());  // read as a plain cloud, the default says nothing

  // A quarter turn about x (w = x = sqrt(1/2)) takes +z to -y and -y to -z; the translation is the sensor.
  const std::string turned = write("turned.pcd", header + "VIEWPOINT 1 2 3 0.70710678 0.70710678 0 0\nPOINTS 1\nDATA ascii\n0 0 2\n");
  view = read_camera_view(turned, 57, 43);
  ASSERT_TRUE(view.ok()) << view.error().message;
  EXPECT_EQ(*view->sensor, Vec3(1, 2, 3));
  EXPECT_TRUE(view->frame->axis.isApprox(-Vec3::UnitY(), 1e-5f)) << view->frame->axis.transpose();
  EXPECT_TRUE(view->frame->up.isApprox(-Vec3::UnitZ(), 1e-5f)) << view->frame->up.transpose();

  Cloud xyz = random_cloud(5, 1);
  ASSERT_TRUE(write_cloud(path("plain.xyz"), xyz).ok());
  auto not_pcd = read_camera_view(path("plain.xyz"), 57, 43);
  ASSERT_FALSE(not_pcd.ok());
  EXPECT_NE(not_pcd.error().message.find("plain.xyz"), std::string::npos);
  EXPECT_NE(not_pcd.error().message.find("VIEWPOINT"), std::string::npos);
  auto bad_fov = read_camera_view(kinect, 57, 180);
  ASSERT_FALSE(bad_fov.ok());
  EXPECT_EQ(bad_fov.error().code, ErrorCode::kInvalidArgument);
  const std::string zero = write("zero.pcd", header + "VIEWPOINT 0 0 0 0 0 0 0\nPOINTS 1\nDATA ascii\n0 0 2\n");
  auto no_rotation = read_camera_view(zero, 57, 43);
  ASSERT_FALSE(no_rotation.ok());
  EXPECT_NE(no_rotation.error().message.find("not a rotation"), std::string::npos);
}

TEST_F(IoTest, CloudWithoutSensorAndWithNanRoundTrips) {
  Cloud cloud;
  cloud.points = {Vec3(1, 2, 3), Vec3(std::nanf(""), 0, 0), Vec3(-1, -2, -3)};
  for (const char* ext : {".pcd", ".ply", ".xyz"}) {
    SCOPED_TRACE(ext);
    const std::string p = path(std::string("nan") + ext);
    ASSERT_TRUE(write_cloud(p, cloud).ok());
    Expected<Cloud> back = read_cloud(p);
    ASSERT_TRUE(back.ok()) << back.error().message;
    ASSERT_EQ(back->points.size(), 3u);
    EXPECT_FALSE(back->sensor.has_value());
    EXPECT_TRUE(std::isnan(back->points[1].x()));  // kept: cleaning is another stage's job
    EXPECT_EQ(back->points[2], Vec3(-1, -2, -3));
  }
}

TEST_F(IoTest, EmptyCloudRoundTrips) {
  for (const char* ext : {".pcd", ".ply"}) {
    const std::string p = path(std::string("empty") + ext);
    ASSERT_TRUE(write_cloud(p, Cloud{}).ok());
    Expected<Cloud> back = read_cloud(p);
    ASSERT_TRUE(back.ok()) << ext << ": " << back.error().message;
    EXPECT_TRUE(back->points.empty());
  }
}

TEST_F(IoTest, UnknownExtensionsAreErrors) {
  Expected<Cloud> c = read_cloud(write("a.las", "LASF"));
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(c.error().message.find("a.las"), std::string::npos);
  EXPECT_FALSE(read_mesh(write("b.pcd", "x")).ok());
  EXPECT_FALSE(write_cloud(path("c.las"), Cloud{}).ok());
}

TEST_F(IoTest, MissingFileIsNotFound) {
  Expected<Mesh> m = read_mesh(path("nope.off"));
  ASSERT_FALSE(m.ok());
  EXPECT_EQ(m.error().code, ErrorCode::kNotFound);
  EXPECT_NE(m.error().message.find("nope.off"), std::string::npos);
}

TEST_F(IoTest, AFolderIsNamedAsOne) {
  std::filesystem::create_directories(path("scans.ply"));  // even with a file's extension
  for (const std::string& folder : {path("scans.ply"), dir_.string()}) {
    Expected<Cloud> c = read_cloud(folder);
    ASSERT_FALSE(c.ok());
    EXPECT_EQ(c.error().message, folder + ": is a folder, not a file");
    Expected<Mesh> m = read_mesh(folder);
    ASSERT_FALSE(m.ok());
    EXPECT_EQ(m.error().message, folder + ": is a folder, not a file");
  }
}

// ---- mesh formats ----

void expect_square_pyramid(const Mesh& m) {
  ASSERT_EQ(m.vertices.size(), 5u);
  EXPECT_EQ(m.vertices[4], Vec3(0.5f, 0.5f, 1.0f));
  ASSERT_EQ(m.faces.size(), 3u);  // one quad (fan: 2 triangles) + one triangle
  EXPECT_EQ(m.faces[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(m.faces[1], Eigen::Vector3i(0, 2, 3));
  EXPECT_EQ(m.faces[2], Eigen::Vector3i(0, 1, 4));
}

TEST_F(IoTest, OffWithCommentsQuadsAndTrailingText) {
  const std::string text =
      "OFF\n# a comment\n5 2 0\n0 0 0\n1 0 0 # inline\n\n1 1 0\n0 1 0\n0.5 0.5 1\n"
      "4 0 1 2 3 255 0 0\n3 0 1 4\nsome trailing junk 1 2 3\n";
  Expected<Mesh> m = read_mesh(write("pyr.OFF", text));  // extension is case-insensitive
  ASSERT_TRUE(m.ok()) << m.error().message;
  expect_square_pyramid(*m);
  Expected<Mesh> same_line = read_mesh(write("p2.off", "OFF 5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n"
                                                       "4 0 1 2 3\n3 0 1 4\n"));
  ASSERT_TRUE(same_line.ok()) << same_line.error().message;
  expect_square_pyramid(*same_line);
  Expected<Mesh> tight = read_mesh(write("tight.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2"));
  ASSERT_TRUE(tight.ok()) << tight.error().message;  // smallest file, no final newline
  EXPECT_EQ(tight->faces.size(), 1u);
  Expected<Cloud> c = read_cloud(path("pyr.OFF"));
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->points.size(), 5u);
}

TEST_F(IoTest, ObjIndexFormsAndNegativeIndices) {
  const std::string text =
      "# obj\nmtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n"
      "f 1/1/1 2/1/1 3//1 4\nv 0.5 0.5 1.0\nf -5 -4 -1\n";
  Expected<Mesh> m = read_mesh(write("pyr.obj", text));
  ASSERT_TRUE(m.ok()) << m.error().message;
  expect_square_pyramid(*m);
}

TEST_F(IoTest, PlyAsciiWithExtraPropertiesAndElements) {
  const std::string text =
      "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 5\nproperty float x\n"
      "property uchar red\nproperty float y\nproperty float z\nelement face 2\n"
      "property list uchar int vertex_indices\nproperty float quality\nelement edge 1\n"
      "property int vertex1\nproperty int vertex2\nend_header\n"
      "0 1 0 0\n1 2 0 0\n1 3 1 0\n0 4 1 0\n0.5 5 0.5 1\n4 0 1 2 3 0.5\n3 0 1 4 1\n0 1\n";
  Expected<Mesh> m = read_mesh(write("pyr.ply", text));
  ASSERT_TRUE(m.ok()) << m.error().message;
  expect_square_pyramid(*m);
}

std::string binary_pyramid_ply(bool big) {
  std::string s = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\nelement vertex 5\nproperty double x\nproperty double y\nproperty float z\n"
                  "property ushort flags\nelement face 2\nproperty list uchar uint vertex_indices\n"
                  "end_header\n";
  const double v[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}};
  for (const auto& p : v) {
    put(s, p[0], big);
    put(s, p[1], big);
    put(s, float(p[2]), big);
    put(s, uint16_t(0xBEEF), big);
  }
  put(s, uint8_t(4), big);
  for (uint32_t i : {0u, 1u, 2u, 3u}) put(s, i, big);
  put(s, uint8_t(3), big);
  for (uint32_t i : {0u, 1u, 4u}) put(s, i, big);
  return s;
}

TEST_F(IoTest, PlyBinaryBothEndiannesses) {
  for (bool big : {false, true}) {
    SCOPED_TRACE(big ? "big" : "little");
    Expected<Mesh> m = read_mesh(write(big ? "big.ply" : "little.ply", binary_pyramid_ply(big)));
    ASSERT_TRUE(m.ok()) << m.error().message;
    expect_square_pyramid(*m);
  }
}

// ---- cloud formats ----

TEST_F(IoTest, PcdAsciiFieldsAnywhereAndViewpoint) {
  const std::string text =
      "# .PCD v0.7\nVERSION 0.7\nFIELDS rgb x normal y z\nSIZE 4 4 4 4 4\nTYPE F F F F F\n"
      "COUNT 1 1 3 1 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 1 2 3 1 0 0 0\nPOINTS 3\nDATA ascii\n"
      "7 1 0 0 1 2 3\n7 nan 0 0 1 nan nan\n7 -4 0 0 1 5 6.5\n";
  Expected<Cloud> c = read_cloud(write("a.pcd", text));
  ASSERT_TRUE(c.ok()) << c.error().message;
  ASSERT_EQ(c->points.size(), 3u);
  EXPECT_EQ(c->points[0], Vec3(1, 2, 3));
  EXPECT_TRUE(std::isnan(c->points[1].x()));
  EXPECT_EQ(c->points[2], Vec3(-4, 5, 6.5f));
  ASSERT_TRUE(c->sensor.has_value());
  EXPECT_EQ(*c->sensor, Vec3(1, 2, 3));
}

TEST_F(IoTest, PcdBinaryMixedFieldTypes) {
  std::string s =
      "VERSION .7\nFIELDS intensity x y z label\nSIZE 2 4 8 4 4\nTYPE U F F F U\nCOUNT 1 1 1 1 1\n"
      "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA binary\n";
  for (int i = 0; i < 2; ++i) {
    put(s, uint16_t(9), false);
    put(s, float(i + 0.5f), false);
    put(s, double(-i), false);
    put(s, float(10 * i), false);
    put(s, uint32_t(1), false);
  }
  Expected<Cloud> c = read_cloud(write("b.pcd", s));
  ASSERT_TRUE(c.ok()) << c.error().message;
  ASSERT_EQ(c->points.size(), 2u);
  EXPECT_EQ(c->points[1], Vec3(1.5f, -1, 10));
  EXPECT_FALSE(c->sensor.has_value());  // identity viewpoint: no sensor
}

TEST_F(IoTest, XyzSeparatorsCommentsExtraColumnsAndHeader) {
  const std::string text = "x,y,z,intensity\n# comment\n1,2,3,9\n 4 5 6 7 8\n\n7\t8\t9 # trailing\n";
  Expected<Cloud> c = read_cloud(write("p.xyz", text));
  ASSERT_TRUE(c.ok()) << c.error().message;
  ASSERT_EQ(c->points.size(), 3u);
  EXPECT_EQ(c->points[0], Vec3(1, 2, 3));
  EXPECT_EQ(c->points[1], Vec3(4, 5, 6));
  EXPECT_EQ(c->points[2], Vec3(7, 8, 9));
}

// ---- malformed input: an error naming the file (and the line or byte offset); never a crash ----

struct Bad {
  const char* name;  // file name (its extension picks the reader)
  std::string bytes;
  const char* where;  // expected in the message besides the file name
};

std::string pad(size_t n) { return std::string(n, ' '); }

std::vector<Bad> bad_inputs() {
  std::string truncated_list = "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
                               "property float y\nproperty float z\nelement face 1\n"
                               "property list uchar int vertex_indices\nend_header\n";
  put(truncated_list, 0.f, false), put(truncated_list, 0.f, false), put(truncated_list, 0.f, false);
  put(truncated_list, uint8_t(200), false);
  put(truncated_list, int32_t(0), false);
  std::string short_pcd = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 10\nPOINTS 10\nDATA binary\n";
  short_pcd += std::string(12, '\0');
  return {
      {"empty.off", "", "empty"},
      {"empty.pcd", "", "empty"},
      {"nohdr.off", "3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", ":1:"},
      {"badcount.off", "OFF\nthree 1 0\n0 0 0\n", ":2:"},
      {"hugecount.off", "OFF\n999999999 1 0\n0 0 0\n", ":2:"},
      {"bigcount.off", "OFF\n5000 1 0\n0 0 0\n", "exceed"},
      {"toomany.off", "OFF\n99999999999999999999 1 0\n", ":2:"},
      {"trunc.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n#" + pad(60) + "\n", "truncated"},
      {"letters.off", "OFF\n3 1 0\n0 0 0\n1 O 0\n0 1 0\n3 0 1 2\n", ":4:"},
      {"index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", ":6:"},
      {"twogon.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1   \n", ":6:"},
      {"longface.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n9 0 1 2\n", ":6:"},
      {"index.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n", ":3:"},
      {"zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", ":4:"},
      {"letters.obj", "v 0 a 0\n", ":1:"},
      {"novertex.obj", "# nothing\n", "no 'v'"},
      {"nohdr.ply", "plx\nformat ascii 1.0\n", ":1:"},
      {"noend.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "end_header"},
      {"huge.ply", "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\n"
                   "property float z\nend_header\n0 0 0\n", ":3:"},
      {"letters.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                      "property float z\nend_header\n0 0 0\n0 0 x\n", ":9:"},
      {"badtype.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quux x\nend_header\n0\n", ":4:"},
      {"list.ply", truncated_list, "byte offset"},
      {"noxyz.pcd", "FIELDS a b c\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n", "lacks"},
      {"nodata.pcd", "FIELDS x y z\nPOINTS 1\n", "DATA"},
      {"huge.pcd", "FIELDS x y z\nPOINTS 4000000000\nDATA ascii\n1 2 3\n", ":3:"},
      {"compressed.pcd", "FIELDS x y z\nPOINTS 1\nDATA binary_compressed\n", "binary_compressed"},
      {"short.pcd", short_pcd, ":6:"},
      {"trunc.pcd", "FIELDS x y z\nPOINTS 3\nDATA ascii\n1 2 3" + pad(40) + "\n", "truncated"},
      {"letters.pcd", "FIELDS x y z\nPOINTS 2\nDATA ascii\n1 2 3\n1 b 3\n", ":5:"},
      {"size.pcd", "FIELDS x y z\nSIZE 4 4\nPOINTS 1\nDATA ascii\n1 2 3\n", ":2:"},
      {"letters.xyz", "1 2 3\n4 five 6\n", ":2:"},
      {"short.xyz", "1 2 3\n4 5\n", ":2:"},
      // An ascii PLY item is one line: an extra column would shift every later value, a missing one pull
      // the next line's in.
      {"extra.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                    "property float z\nend_header\n0 0 0 7\n1 1 1 7\n", ":8:"},
      {"shortitem.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                        "property float z\nend_header\n0 0\n1 1 1\n2 2 2\n", ":8:"},
      // A PCD whose counts disagree (PCL refuses it too), a row of more values than fields, more rows than
      // points, an organised height of 0.
      {"pointswh.pcd", "FIELDS x y z\nWIDTH 3\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n4 5 6\n7 8 9\n",
       "POINTS 1 but WIDTH x HEIGHT is 3"},
      {"height0.pcd", "FIELDS x y z\nWIDTH 1\nHEIGHT 0\nDATA ascii\n", ":3:"},
      {"extra.pcd", "FIELDS x y z\nPOINTS 1\nDATA ascii\n1 2 3 4\n", ":4:"},
      {"more.pcd", "FIELDS x y z\nPOINTS 1\nDATA ascii\n1 2 3\n4 5 6\n", ":5:"},
      // Not a column header: it has numbers in it.
      {"hex.xyz", "0x10 0 0\n1 2 3\n", ":1:"},
      // Lone carriage returns end lines (classic Mac files): the second line is short.
      {"cr.xyz", "1 2 3\r4 5\r", ":2:"},
  };
}

TEST_F(IoTest, ClassicMacLineEndsAreLineEnds) {
  Expected<Cloud> c = read_cloud(write("mac.xyz", "1 2 3\r4 5 6\r\r7 8 9\r"));
  ASSERT_TRUE(c.ok()) << c.error().message;
  EXPECT_EQ(c->points.size(), 3u);
  Expected<Mesh> m = read_mesh(write("mac.obj", "v 0 0 0\rv 1 0 0\r\nv 0 1 0\rf 1 2 3"));
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->vertices.size(), 3u);
  EXPECT_EQ(m->faces.size(), 1u);
}

TEST_F(IoTest, MalformedInputsGiveErrorsNamingFileAndPlace) {
  for (const Bad& bad : bad_inputs()) {
    SCOPED_TRACE(bad.name);
    const std::string p = write(bad.name, bad.bytes);
    const std::string ext = fs::path(p).extension().string();
    const bool mesh_format = ext == ".off" || ext == ".obj" || ext == ".ply";
    std::string message;
    if (mesh_format) {
      Expected<Mesh> m = read_mesh(p);
      ASSERT_FALSE(m.ok());
      message = m.error().message;
    }
    Expected<Cloud> c = read_cloud(p);  // a mesh file's cloud may be fine (e.g. only faces broken)
    if (!mesh_format) {
      ASSERT_FALSE(c.ok());
      message = c.error().message;
    } else if (!c.ok()) {
      EXPECT_NE(c.error().message.find(bad.name), std::string::npos) << c.error().message;
    }
    EXPECT_NE(message.find(bad.name), std::string::npos) << message;
    EXPECT_NE(message.find(bad.where), std::string::npos) << message;
  }
}

// ---- STL ----

// A binary STL of the given triangles (corners), header starting with "solid" as many exporters write.
std::string binary_stl(const std::vector<std::array<Vec3, 3>>& triangles) {
  std::string s = "solid exported by a CAD tool";
  s.resize(80, ' ');
  put(s, static_cast<uint32_t>(triangles.size()), false);
  for (const auto& t : triangles) {
    for (int a = 0; a < 3; ++a) put(s, 0.f, false);  // stored normal: ignored
    for (const Vec3& c : t)
      for (int a = 0; a < 3; ++a) put(s, c[a], false);
    put(s, uint16_t{0}, false);
  }
  return s;
}

// A unit square pyramid: 4 sides and a base of 2 triangles, 5 distinct corners.
std::vector<std::array<Vec3, 3>> pyramid_triangles() {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(1, 1, 0), d(0, 1, 0), top(0.5f, 0.5f, 1);
  return {{a, c, b}, {a, d, c}, {a, b, top}, {b, c, top}, {c, d, top}, {d, a, top}};
}

void expect_welded_pyramid(const Mesh& m) {
  ASSERT_EQ(m.vertices.size(), 5u);  // 18 stored corners welded into 5 points
  ASSERT_EQ(m.faces.size(), 6u);
  EXPECT_EQ(m.vertices[4], Vec3(0.5f, 0.5f, 1.0f));
  for (const auto& f : m.faces)
    for (int k = 0; k < 3; ++k) EXPECT_LT(f[k], 5);
  EXPECT_EQ(m.faces[2], Eigen::Vector3i(0, 2, 4));  // corners numbered as first met: a, c, b, d, top
}

TEST_F(IoTest, StlBinaryWithASolidHeaderIsReadAsBinary) {
  const std::string p = write("part.stl", binary_stl(pyramid_triangles()));
  Expected<Mesh> m = read_mesh(p);
  ASSERT_TRUE(m.ok()) << m.error().message;
  expect_welded_pyramid(*m);
  Expected<Cloud> c = read_cloud(p);
  ASSERT_TRUE(c.ok()) << c.error().message;
  EXPECT_EQ(c->points.size(), 5u);
  EXPECT_FALSE(c->sensor);
}

TEST_F(IoTest, StlAsciiWithSeveralSolidsAndUpperCase) {
  std::string text = "solid pyramid\n";
  const auto tris = pyramid_triangles();
  for (size_t t = 0; t < tris.size(); ++t) {
    if (t == 3) text += "endsolid pyramid\nSOLID second\n";
    text += "  facet normal 0 0 0\n    outer loop\n";
    for (const Vec3& v : tris[t]) text += "      vertex " + std::to_string(v.x()) + " " + std::to_string(v.y()) + " " + std::to_string(v.z()) + "\n";
    text += "    endloop\n  endfacet\n";
  }
  text += "ENDSOLID second\n";
  Expected<Mesh> m = read_mesh(write("part.STL", text));
  ASSERT_TRUE(m.ok()) << m.error().message;
  expect_welded_pyramid(*m);
}

TEST_F(IoTest, StlTrianglesThatCollapseAreDropped) {
  auto tris = pyramid_triangles();
  tris.push_back({Vec3(1, 1, 0), Vec3(1, 1, 0), Vec3(0, 0, 0)});
  Expected<Mesh> m = read_mesh(write("sliver.stl", binary_stl(tris)));
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->faces.size(), 6u);
}

TEST_F(IoTest, MalformedStlGivesErrorsNamingFileAndPlace) {
  std::string body = binary_stl(pyramid_triangles());
  struct Case {
    std::string name, bytes, where;
  };
  std::string nan_corner = body;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nan_corner.data() + 84 + 12, &nan, 4);  // first corner's x of triangle 0
  const std::vector<Case> cases = {
      {"short.stl", body.substr(0, body.size() - 1), "byte offset 80: binary STL header states 6 triangles"},
      {"tiny.stl", "\x01\x02", "byte offset 2: truncated"},
      {"nan.stl", nan_corner, "byte offset 96: triangle 0 has a non-finite corner"},
      {"zero.stl", binary_stl({}), "no triangles"},
      {"four.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\n", ":7: a facet with more than 3 vertices"},
      {"two.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n", ":6: a facet needs exactly 3"},
      {"letters.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 zero 0\n", ":4: expected 'vertex x y z'"},
      {"stray.stl", "solid x\nvertex 0 0 0\n", ":2: 'vertex' outside"},
      {"open.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", "truncated inside a facet"},
      {"word.stl", "solid x\nfacets 3\n", ":2: unexpected 'facets'"},
      {"text.stl", "hello world, this is not a mesh at all but it is long enough to have a header ........ 1234", "byte offset 80"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Expected<Mesh> m = read_mesh(write(c.name, c.bytes));
    ASSERT_FALSE(m.ok());
    EXPECT_EQ(m.error().code, ErrorCode::kDataLoss);
    EXPECT_NE(m.error().message.find(c.name), std::string::npos) << m.error().message;
    EXPECT_NE(m.error().message.find(c.where), std::string::npos) << m.error().message;
    EXPECT_FALSE(read_cloud(path(c.name)).ok());
  }
}

// ---- regressions found by fuzzing (tests/fuzz) ----

// A face count of 2^64 - 1 wrapped the "n + 1 tokens" check to 0 and read past the face's tokens.
TEST_F(IoTest, OffFaceCountThatWrapsIsAnError) {
  const std::string p = write("wrap.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n18446744073709551615 0 1 2\n");
  Expected<Mesh> m = read_mesh(p);
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.error().message.find("wrap.off:6: expected a face"), std::string::npos) << m.error().message;
}

// A binary body one byte short of POINTS records passed the size check (it allowed for a missing
// newline, as ascii may) and the last record was read one byte past the end of the data.
TEST_F(IoTest, PcdBinaryHeaderOverATextBodyIsAnError) {
  const std::string header = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA ";
  const std::string body = "0.125 1.5 -2\n0.25 1.75 -2.5\n0.5 2 -3e-1\n";
  ASSERT_TRUE(read_cloud(write("ascii.pcd", header + "ascii\n" + body)).ok());
  Expected<Cloud> c = read_cloud(write("mislabelled.pcd", header + "binary\n" + body));
  ASSERT_FALSE(c.ok());
  EXPECT_NE(c.error().message.find("mislabelled.pcd"), std::string::npos) << c.error().message;
  EXPECT_NE(c.error().message.find("DATA binary, but the body is text"), std::string::npos) << c.error().message;
}

TEST_F(IoTest, PcdBinaryBodyOneByteShortIsAnError) {
  std::string s = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n";
  for (float v : {1.f, 2.f, 3.f, 4.f, 5.f}) put(s, v, false);
  s += "ab1";  // 23 of the 24 bytes
  Expected<Cloud> c = read_cloud(write("short.pcd", s));
  ASSERT_FALSE(c.ok());
  EXPECT_NE(c.error().message.find("exceeds what the file can hold"), std::string::npos) << c.error().message;
  s.push_back('2');
  EXPECT_TRUE(read_cloud(write("whole.pcd", s)).ok());
}

}  // namespace
}  // namespace glimpse

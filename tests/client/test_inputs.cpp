#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "client/inputs.h"
#include "common/meshes.h"
#include "common/temp_dir.h"
#include "glimpse/io/files.h"

namespace glimpse::client {
namespace {

namespace fs = std::filesystem;

class InputsTest : public ::testing::Test {
 protected:
  // A closed box of 12 triangles, 1 x 1 x 2 m, standing on the ground.
  std::string WriteBox(const fs::path& path) { return glimpse::testing::WriteOffBox(path, 1, 1, 2); }

  std::string WriteCloud(const fs::path& path, size_t n, bool sensor = false) {
    fs::create_directories(path.parent_path());
    Cloud c;
    for (size_t i = 0; i < n; ++i) c.points.push_back(Vec3(float(i) * 0.01f, 0.5f, 1.0f));
    if (sensor) c.sensor = Vec3(0, -3, 1);
    EXPECT_TRUE(write_cloud(path.string(), c).ok());
    return path.string();
  }

  glimpse::testing::TempDir tmp_{"client-inputs"};
  fs::path dir_ = tmp_.path();
};

TEST_F(InputsTest, IsInputFileByExtension) {
  for (const char* ok : {"a.pcd", "a.PLY", "b.xyz", "c.off", "d.obj", "e.txt", "f.csv", "g.stl"}) EXPECT_TRUE(IsInputFile(ok));
  for (const char* no : {"README", "up_axis", ".ply.bak", "a.stl.gz"}) EXPECT_FALSE(IsInputFile(no)) << no;
}

TEST_F(InputsTest, ListTrainDirSortsCategoriesAndSkipsTheRest) {
  WriteCloud(dir_ / "table" / "b.xyz", 5);
  WriteCloud(dir_ / "table" / "a.pcd", 5);
  WriteBox(dir_ / "chair" / "1.off");
  WriteCloud(dir_ / ".hidden" / "x.xyz", 5);
  WriteCloud(dir_ / "loose.xyz", 5);
  std::ofstream(dir_ / "chair" / "notes.md") << "not a cloud";
  fs::create_directories(dir_ / "empty");
  auto files = ListTrainDir(dir_.string());
  ASSERT_TRUE(files.ok()) << files.error().message;
  ASSERT_EQ(files->size(), 3u);
  EXPECT_EQ((*files)[0].category, "chair");
  EXPECT_EQ((*files)[0].object_id, "chair/1");
  EXPECT_EQ((*files)[1].category, "table");
  EXPECT_EQ((*files)[1].object_id, "table/a");
  EXPECT_EQ((*files)[2].object_id, "table/b");
}

TEST_F(InputsTest, ListTrainDirErrors) {
  auto missing = ListTrainDir((dir_ / "nope").string());
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::kNotFound);
  EXPECT_NE(missing.error().message.find("nope"), std::string::npos);
  auto empty = ListTrainDir(dir_.string());
  ASSERT_FALSE(empty.ok());
  EXPECT_NE(empty.error().message.find(dir_.string()), std::string::npos);
}

TEST_F(InputsTest, MeshGivesSingleViewsWithSensors) {
  const std::string box = WriteBox(dir_ / "box.off");
  auto file = LoadFile(box);
  ASSERT_TRUE(file.ok()) << file.error().message;
  EXPECT_TRUE(file->is_mesh);
  ViewOptions options;
  options.mesh_points = 3000;
  options.views = 3;
  auto clouds = TrainingClouds(box, options);
  ASSERT_TRUE(clouds.ok()) << clouds.error().message;
  ASSERT_EQ(clouds->size(), 3u);
  for (const Cloud& c : *clouds) {
    EXPECT_TRUE(c.sensor.has_value());
    EXPECT_GT(c.points.size(), 300u);
    EXPECT_LT(c.points.size(), 3000u);  // a view sees part of the surface
  }
  options.views = 0;
  auto whole = TrainingClouds(box, options);
  ASSERT_TRUE(whole.ok());
  ASSERT_EQ(whole->size(), 1u);
  EXPECT_NEAR(double((*whole)[0].points.size()), 3000.0, 30.0);
  EXPECT_FALSE((*whole)[0].sensor.has_value());
}

TEST_F(InputsTest, CloudFileIsUsedAsItIs) {
  const std::string path = WriteCloud(dir_ / "c.ply", 42, /*sensor=*/true);
  auto clouds = TrainingClouds(path, ViewOptions{});
  ASSERT_TRUE(clouds.ok()) << clouds.error().message;
  ASSERT_EQ(clouds->size(), 1u);
  EXPECT_EQ((*clouds)[0].points.size(), 42u);
  ASSERT_TRUE((*clouds)[0].sensor.has_value());
  auto to_classify = CloudToClassify(path, ViewOptions{});
  ASSERT_TRUE(to_classify.ok());
  EXPECT_EQ(to_classify->points.size(), 42u);
}

TEST_F(InputsTest, SingleViewsAndSingleViewAgree) {
  auto file = LoadFile(WriteBox(dir_ / "box.off"));
  ASSERT_TRUE(file.ok());
  auto full = SampleMesh(file->mesh, 2000, 1);
  ASSERT_TRUE(full.ok());
  const auto six = SingleViews(*full, 6, 100.0);
  ASSERT_EQ(six.size(), 6u);
  EXPECT_EQ(SingleViews(*full, 60, 100.0).size(), 6u);
  const Cloud third = SingleView(*full, 3, 100.0);
  EXPECT_EQ(third.points.size(), six[3].points.size());
  EXPECT_EQ(third.sensor, six[3].sensor);
  EXPECT_TRUE(SingleViews(Cloud{}, 6, 100.0).empty());
}

TEST_F(InputsTest, MissingFileErrorNamesIt) {
  const std::string path = (dir_ / "missing.ply").string();
  auto cloud = CloudToClassify(path, ViewOptions{});
  ASSERT_FALSE(cloud.ok());
  EXPECT_EQ(cloud.error().code, ErrorCode::kNotFound);
  EXPECT_NE(cloud.error().message.find(path), std::string::npos);
  auto clouds = TrainingClouds((dir_ / "missing.off").string(), ViewOptions{});
  ASSERT_FALSE(clouds.ok());
  EXPECT_NE(clouds.error().message.find("missing.off"), std::string::npos);
}

}  // namespace
}  // namespace glimpse::client

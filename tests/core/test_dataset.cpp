#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>

#include "common/temp_dir.h"
#include "glimpse/views/dataset.h"
#include "glimpse/views/placement.h"

namespace glimpse {
namespace {

namespace fs = std::filesystem;

// A thin box 0.2 x 2 x 0.5 along +y (the SHREC default up), written as OFF.
const char* kTallAlongY =
    "OFF\n8 12 0\n0 0 0\n0.2 0 0\n0 2 0\n0.2 2 0\n0 0 0.5\n0.2 0 0.5\n0 2 0.5\n0.2 2 0.5\n"
    "3 0 2 1\n3 1 2 3\n3 4 5 6\n3 5 7 6\n3 0 1 4\n3 1 5 4\n3 2 6 3\n3 3 6 7\n3 0 4 2\n3 2 4 6\n"
    "3 1 3 5\n3 3 7 5\n";

class DatasetTest : public ::testing::Test {
 protected:
  void file(const std::string& rel, const std::string& text) {
    fs::create_directories((root_ / rel).parent_path());
    std::ofstream(root_ / rel) << text;
  }
  glimpse::testing::TempDir tmp_{"dataset"};
  fs::path root_ = tmp_.path();
};

TEST_F(DatasetTest, ScanSortsByCategoryThenNumericIdAndReadsUpAxes) {
  file("human/10.off", kTallAlongY);
  file("human/2.off", kTallAlongY);
  file("human/notes.txt", "not a mesh");
  file("chair/7.OFF", kTallAlongY);
  file("widget/w1.off", kTallAlongY);
  file(".hidden/1.off", kTallAlongY);
  file("human/._10.off", "macOS resource fork, not a mesh");  // hidden files are not objects
  file("human/.old.off", kTallAlongY);
  fs::create_directories(root_ / "empty");
  file("up_axis.csv", "# id,up\n\n10,+z\n7, -x  # trailing comment\n999,+z\n");
  Expected<Dataset> ds = scan_dataset(root_.string());
  ASSERT_TRUE(ds.ok()) << ds.error().message;
  EXPECT_EQ(ds->categories, (std::vector<std::string>{"chair", "human", "widget"}));
  ASSERT_EQ(ds->objects.size(), 4u);
  EXPECT_EQ(ds->objects[0].id, "7");
  EXPECT_EQ(ds->objects[0].up, Vec3(-1, 0, 0));
  EXPECT_EQ(ds->objects[1].id, "2");  // 2 before 10: numeric order
  EXPECT_EQ(ds->objects[1].up, Vec3(0, 1, 0));
  EXPECT_EQ(ds->objects[2].id, "10");
  EXPECT_EQ(ds->objects[2].up, Vec3(0, 0, 1));
  EXPECT_EQ(ds->objects[1].size.measure, CategorySize::kHeight);
  EXPECT_FLOAT_EQ(ds->objects[1].size.min_m, 1.55f);
  EXPECT_EQ(ds->objects[3].category, "widget");  // unknown category: documented default
  EXPECT_EQ(ds->objects[3].size.measure, CategorySize::kLargestExtent);
  EXPECT_FLOAT_EQ(ds->objects[3].size.min_m, 0.3f);
  EXPECT_FLOAT_EQ(ds->objects[3].size.max_m, 1.0f);
  EXPECT_EQ(ds->unmatched_up_rows, 1u);  // 999
  EXPECT_TRUE(ds->has_up_axes);
  EXPECT_FALSE(ds->has_sizes);
}

TEST_F(DatasetTest, ManifestOfCategoryFileKeysVectorsSizesAndPoses) {
  file("chair/psb_D1.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n");
  file("chair/psb_D2.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n");
  file("mechanic/abc_1.stl", "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid a\n");
  file("lamp/l1.off", kTallAlongY);
  file("up_axis.csv", "# category/file,up\nchair/psb_D1.obj,-0.762 0.080 -0.642\nchair/psb_D2,+z\nmechanic/abc_1.stl,-y\n");
  file("sizes.csv", "# category,height|extent,min_m,max_m\nlamp,height,0.30,0.60\nmechanic,extent,0.05,0.10,any-pose\nchair,height,0.4,0.5,upright\n");
  Expected<Dataset> ds = scan_dataset(root_.string());
  ASSERT_TRUE(ds.ok()) << ds.error().message;
  ASSERT_EQ(ds->objects.size(), 4u);
  EXPECT_TRUE(ds->has_sizes);
  EXPECT_EQ(ds->unmatched_up_rows, 0u);
  const DatasetObject& d1 = ds->objects[0];
  EXPECT_EQ(d1.id, "psb_D1");
  EXPECT_TRUE(d1.up.isApprox(Vec3(-0.762f, 0.080f, -0.642f).normalized()));
  EXPECT_EQ(ds->objects[1].up, Vec3(0, 0, 1));
  EXPECT_FLOAT_EQ(d1.size.max_m, 0.5f);  // the folder's row replaces the default chair range
  EXPECT_FALSE(d1.size.any_pose);
  EXPECT_EQ(ds->objects[2].category, "lamp");
  EXPECT_EQ(ds->objects[2].size.measure, CategorySize::kHeight);
  EXPECT_FLOAT_EQ(ds->objects[2].size.min_m, 0.3f);
  EXPECT_EQ(ds->objects[3].up, Vec3(0, -1, 0));
  EXPECT_TRUE(ds->objects[3].size.any_pose);
  EXPECT_FLOAT_EQ(ds->objects[3].size.max_m, 0.1f);
  // The tilted chair stands up: the listed vector becomes +z (its tip is the highest point).
  Expected<Mesh> m = load_object(d1, 3);
  ASSERT_TRUE(m.ok()) << m.error().message;
  const Eigen::Matrix3f r = upright_rotation(d1.up);
  EXPECT_TRUE((r * d1.up).isApprox(Vec3::UnitZ(), 1e-5f));
}

TEST_F(DatasetTest, DefaultsKnowTheFiveCategoriesAndThatPartsHaveNoUp) {
  for (const CategorySize& c : default_category_sizes()) EXPECT_EQ(c.any_pose, c.category == "mechanic") << c.category;
  EXPECT_FALSE(category_size("bicycle").any_pose);
}

TEST_F(DatasetTest, SizingByUnitOrCommonHeight) {
  file("human/1.off", kTallAlongY);  // 2 units tall along +y
  Expected<Dataset> ds = scan_dataset(root_.string());
  ASSERT_TRUE(ds.ok()) << ds.error().message;
  Expected<Mesh> cm = load_object(ds->objects[0], 1, {Sizing::kUnit, 0.01f});
  ASSERT_TRUE(cm.ok());
  EXPECT_NEAR(bounds(cm->vertices).extent().z(), 0.02f, 1e-6f);
  Expected<Mesh> tall = load_object(ds->objects[0], 1, {Sizing::kHeight, 1.0f});
  ASSERT_TRUE(tall.ok());
  EXPECT_NEAR(bounds(tall->vertices).extent().z(), 1.0f, 1e-6f);
}

TEST_F(DatasetTest, BadSizeRowsNameFileAndLine) {
  file("human/1.off", kTallAlongY);
  for (const char* csv : {"# c\nhuman,height,1\n", "# c\nhuman,width,1,2\n", "# c\nhuman,height,2,1\n",
                          "# c\nhuman,height,0,1\n", "# c\nhuman,height,1,2,sideways\n",
                          "# c\nhuman,height,1,2\nhuman,height,1,2\n", "# c\n,height,1,2\n"}) {
    SCOPED_TRACE(csv);
    file("sizes.csv", csv);
    Expected<Dataset> ds = scan_dataset(root_.string());
    ASSERT_FALSE(ds.ok());
    const std::string& msg = ds.error().message;
    EXPECT_NE(msg.find("sizes.csv:"), std::string::npos) << msg;
    EXPECT_TRUE(msg.find(":2:") != std::string::npos || msg.find(":3:") != std::string::npos) << msg;
  }
}

// A file of vertices alone in a mesh format is a point cloud: cutting views from it would silently make
// views of a view, so loading it as an object is an error that names the file.
TEST_F(DatasetTest, AMeshFileWithoutFacesIsRefusedAsAnObject) {
  file("chair/scan.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                         "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n");
  file("chair/cloud.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n");
  Expected<Dataset> ds = scan_dataset(root_.string());
  ASSERT_TRUE(ds.ok()) << ds.error().message;
  ASSERT_EQ(ds->objects.size(), 2u);
  for (const DatasetObject& o : ds->objects) {
    Expected<Mesh> m = load_object(o, 1);
    ASSERT_FALSE(m.ok()) << o.path;
    EXPECT_EQ(m.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(m.error().message.find(o.path + ": no faces"), std::string::npos) << m.error().message;
  }
}

TEST_F(DatasetTest, SizeTableCanBeOverridden) {
  file("human/1.off", kTallAlongY);
  Expected<Dataset> ds = scan_dataset(root_.string(), {{"human", CategorySize::kHeight, 0.1f, 0.2f}});
  ASSERT_TRUE(ds.ok()) << ds.error().message;
  EXPECT_FLOAT_EQ(ds->objects[0].size.max_m, 0.2f);
  Expected<Mesh> m = load_object(ds->objects[0], 1);
  ASSERT_TRUE(m.ok());
  const float h = bounds(m->vertices).extent().z();
  EXPECT_GE(h, 0.1f - 1e-5f);
  EXPECT_LE(h, 0.2f + 1e-5f);
}

TEST_F(DatasetTest, MissingOrEmptyFolderNamesIt) {
  Expected<Dataset> missing = scan_dataset((root_ / "nope").string());
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::kNotFound);
  EXPECT_NE(missing.error().message.find("nope"), std::string::npos);
  fs::create_directories(root_ / "chair");
  Expected<Dataset> empty = scan_dataset(root_.string());
  ASSERT_FALSE(empty.ok());
  EXPECT_NE(empty.error().message.find(root_.string()), std::string::npos);
}

TEST_F(DatasetTest, BadUpAxisRowsNameFileAndLine) {
  file("human/1.off", kTallAlongY);
  for (const char* csv : {"# c\n1,+w\n", "# c\n1\n", "# c\n,+z\n", "# c\n1,+z,2\n", "# c\n1,+z\n1,-z\n",
                          "# c\n1,0 0 0\n", "# c\nhuman/1.off,1 2\n"}) {
    SCOPED_TRACE(csv);
    file("up_axis.csv", csv);
    Expected<Dataset> ds = scan_dataset(root_.string());
    ASSERT_FALSE(ds.ok());
    const std::string& msg = ds.error().message;
    EXPECT_NE(msg.find("up_axis.csv:"), std::string::npos) << msg;
    EXPECT_TRUE(msg.find(":2:") != std::string::npos || msg.find(":3:") != std::string::npos) << msg;
  }
}

TEST_F(DatasetTest, LoadStandsScalesAndGroundsDeterministically) {
  file("human/1.off", kTallAlongY);
  file("human/2.off", kTallAlongY);
  file("mechanic/5.off", kTallAlongY);
  Expected<Dataset> ds = scan_dataset(root_.string());
  ASSERT_TRUE(ds.ok()) << ds.error().message;
  std::set<float> heights;
  for (const DatasetObject& o : ds->objects) {
    SCOPED_TRACE(o.path);
    Expected<Mesh> m = load_object(o, 11);
    ASSERT_TRUE(m.ok()) << m.error().message;
    const Bounds b = bounds(m->vertices);
    EXPECT_NEAR(b.min.z(), 0.f, 1e-6f);
    EXPECT_NEAR(b.centre().x(), 0.f, 1e-6f);
    EXPECT_NEAR(b.centre().y(), 0.f, 1e-6f);
    const float measured = o.size.measure == CategorySize::kHeight ? b.extent().z() : b.extent().maxCoeff();
    EXPECT_NEAR(measured, object_size_m(o, 11), 1e-5f);
    EXPECT_GE(measured, o.size.min_m - 1e-5f);
    EXPECT_LE(measured, o.size.max_m + 1e-5f);
    if (o.size.measure == CategorySize::kHeight) {  // the 2 m y side now points up
      EXPECT_GT(b.extent().z(), 3 * b.extent().x());
    }
    Expected<Mesh> again = load_object(o, 11);
    ASSERT_TRUE(again.ok());
    EXPECT_EQ(again->vertices, m->vertices);
    heights.insert(measured);
  }
  EXPECT_EQ(heights.size(), 3u);  // two humans get different sizes
  EXPECT_NE(object_size_m(ds->objects[0], 11), object_size_m(ds->objects[0], 12));
}

TEST_F(DatasetTest, LoadReportsBrokenMesh) {
  file("chair/3.off", "OFF\n3 1 0\n0 0 0\n");
  Expected<Dataset> ds = scan_dataset(root_.string());
  ASSERT_TRUE(ds.ok());
  Expected<Mesh> m = load_object(ds->objects[0], 1);
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.error().message.find("3.off"), std::string::npos);
}

// ---- the real SHREC 2007 subset (not in the repository: academic licence) ----

std::string shrec_dir() {
  if (const char* env = std::getenv("GLIMPSE_SHREC_DIR")) return env;
  return GLIMPSE_SOURCE_DIR "/../shared/data/shrec07";
}

TEST(Shrec07, AllHundredLoadUprightAtRealLifeSize) {
  const std::string dir = shrec_dir();
  if (!fs::is_directory(dir)) GTEST_SKIP() << "SHREC 2007 subset not found at " << dir << " (set GLIMPSE_SHREC_DIR)";
  Expected<Dataset> ds = scan_dataset(dir);
  ASSERT_TRUE(ds.ok()) << ds.error().message;
  EXPECT_EQ(ds->categories, (std::vector<std::string>{"chair", "fourleg", "human", "mechanic", "table"}));
  ASSERT_EQ(ds->objects.size(), 100u);
  size_t not_y = 0;
  for (const DatasetObject& o : ds->objects) {
    SCOPED_TRACE(o.path);
    not_y += o.up != Vec3::UnitY();
    Expected<Mesh> m = load_object(o, 2024);
    ASSERT_TRUE(m.ok()) << m.error().message;
    EXPECT_GT(m->vertices.size(), 1000u);
    const Bounds b = bounds(m->vertices);
    EXPECT_NEAR(b.min.z(), 0.f, 1e-5f);
    const float measured = o.size.measure == CategorySize::kHeight ? b.extent().z() : b.extent().maxCoeff();
    EXPECT_GE(measured, o.size.min_m - 1e-4f);
    EXPECT_LE(measured, o.size.max_m + 1e-4f);
    if (o.category == "human") {  // upright people are taller than they are wide
      EXPECT_GT(b.extent().z(), 0.8f * std::max(b.extent().x(), b.extent().y()));
    }
  }
  EXPECT_EQ(not_y, 19u);
}

// ---- the second source: Princeton Shape Benchmark meshes and ABC CAD parts (research licence) ----

std::string psb_dir() {
  if (const char* env = std::getenv("GLIMPSE_PSB_DIR")) return env;
  return GLIMPSE_SOURCE_DIR "/../shared/data/psb";
}

TEST(Psb, All150LoadUprightIncludingTiltedOnesAndBinaryStl) {
  const std::string dir = psb_dir();
  if (!fs::is_directory(dir)) GTEST_SKIP() << "PSB set not found at " << dir << " (set GLIMPSE_PSB_DIR)";
  Expected<Dataset> ds = scan_dataset(dir);
  ASSERT_TRUE(ds.ok()) << ds.error().message;
  EXPECT_EQ(ds->categories, (std::vector<std::string>{"chair", "fourleg", "human", "mechanic", "table"}));
  ASSERT_EQ(ds->objects.size(), 150u);
  EXPECT_EQ(ds->unmatched_up_rows, 0u);
  size_t tilted = 0, parts = 0;
  for (const DatasetObject& o : ds->objects) {
    SCOPED_TRACE(o.path);
    tilted += o.up.cwiseAbs().maxCoeff() < 0.999f;
    Expected<Mesh> m = load_object(o, 2024);
    ASSERT_TRUE(m.ok()) << m.error().message;
    const Bounds b = bounds(m->vertices);
    EXPECT_NEAR(b.min.z(), 0.f, 1e-5f);
    if (o.category == "human") {  // upright people are taller than they are wide
      EXPECT_GT(b.extent().z(), 0.8f * std::max(b.extent().x(), b.extent().y()));
    }
    if (o.category == "mechanic") {
      ++parts;
      EXPECT_TRUE(o.size.any_pose);
      EXPECT_GT(m->faces.size(), 10u);
    }
  }
  EXPECT_EQ(parts, 6u);
  EXPECT_GE(tilted, 3u);  // psb/README lists chairs and tables of the D series 10-40 degrees off
}

}  // namespace
}  // namespace glimpse

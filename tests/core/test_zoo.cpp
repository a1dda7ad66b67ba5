#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "glimpse/views/dataset.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/hidden_point_removal.h"
#include "glimpse/views/zoo.h"

namespace glimpse {
namespace {

TEST(Zoo, CategoriesAreTheSHRECFolders) {
  EXPECT_EQ(zoo_categories(), (std::vector<std::string>{"human", "chair", "table", "mechanic", "fourleg"}));
  Expected<Mesh> bad = make_zoo_shape("spaceship", 1);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(bad.error().message.find("spaceship"), std::string::npos);
}

TEST(Zoo, EveryCategoryBuildsValidUprightGroundedMeshesInItsSizeRange) {
  for (const std::string& category : zoo_categories()) {
    const CategorySize size = category_size(category);
    for (uint64_t seed = 0; seed < 40; ++seed) {
      SCOPED_TRACE(category + " seed " + std::to_string(seed));
      Expected<Mesh> m = make_zoo_shape(category, seed);
      ASSERT_TRUE(m.ok()) << m.error().message;
      ASSERT_GT(m->vertices.size(), 2000u);
      ASSERT_LT(m->vertices.size(), 20000u);
      ASSERT_GT(m->faces.size(), m->vertices.size());
      for (const Vec3& v : m->vertices) ASSERT_TRUE(v.allFinite());
      for (const Eigen::Vector3i& f : m->faces) {
        ASSERT_TRUE((f.array() >= 0).all() && (f.array() < int(m->vertices.size())).all());
        ASSERT_TRUE(f[0] != f[1] && f[1] != f[2] && f[0] != f[2]);
      }
      const Bounds b = bounds(m->vertices);
      EXPECT_NEAR(b.min.z(), 0.f, 1e-5f);
      EXPECT_NEAR(b.centre().x(), 0.f, 1e-5f);
      EXPECT_NEAR(b.centre().y(), 0.f, 1e-5f);
      const float measured = size.measure == CategorySize::kHeight ? b.extent().z() : b.extent().maxCoeff();
      EXPECT_GE(measured, size.min_m - 1e-4f);
      EXPECT_LE(measured, size.max_m + 1e-4f);
      EXPECT_GT(surface_area(*m), 0.0);
    }
  }
}

TEST(Zoo, DeterministicPerSeedAndSeedsDiffer) {
  for (const std::string& category : zoo_categories()) {
    SCOPED_TRACE(category);
    Expected<Mesh> a = make_zoo_shape(category, 77), b = make_zoo_shape(category, 77), c = make_zoo_shape(category, 78);
    ASSERT_TRUE(a.ok() && b.ok() && c.ok());
    EXPECT_EQ(a->vertices, b->vertices);
    EXPECT_EQ(a->faces, b->faces);
    EXPECT_NE(a->vertices, c->vertices);
  }
}

TEST(Zoo, VertexTargetIsFollowed) {
  Expected<Mesh> small = make_zoo_shape("table", 3, {1500}), big = make_zoo_shape("table", 3, {12000});
  ASSERT_TRUE(small.ok() && big.ok());
  EXPECT_NEAR(double(small->vertices.size()), 1500, 600);
  EXPECT_NEAR(double(big->vertices.size()), 12000, 4000);
}

// Within a category, shapes must differ in more than size: proportions (extent ratios) spread out.
TEST(Zoo, CategoriesVaryInProportions) {
  for (const std::string& category : zoo_categories()) {
    SCOPED_TRACE(category);
    std::vector<float> slenderness, sizes;  // height / horizontal extent, and the height
    for (uint64_t seed = 100; seed < 130; ++seed) {
      Expected<Mesh> m = make_zoo_shape(category, seed, {1500});
      ASSERT_TRUE(m.ok());
      const Vec3 e = bounds(m->vertices).extent();
      slenderness.push_back(e.z() / std::max(e.x(), e.y()));
      sizes.push_back(e.z());
    }
    const auto [lo, hi] = std::minmax_element(slenderness.begin(), slenderness.end());
    EXPECT_GT(*hi / *lo, 1.3f) << "all " << category << " have the same proportions";
    const auto [slo, shi] = std::minmax_element(sizes.begin(), sizes.end());
    EXPECT_GT(*shi - *slo, 0.01f);
  }
}

TEST(Zoo, MakeZooGroupsByCategoryWithReproducibleSeeds) {
  const std::vector<LabelledMesh> zoo = make_zoo(3, 5, {800});
  ASSERT_EQ(zoo.size(), 15u);
  std::map<std::string, int> count;
  for (size_t i = 0; i < zoo.size(); ++i) {
    EXPECT_EQ(zoo[i].category, zoo_categories()[i / 3]);
    ++count[zoo[i].category];
    Expected<Mesh> again = make_zoo_shape(zoo[i].category, zoo[i].seed, {800});
    ASSERT_TRUE(again.ok());
    EXPECT_EQ(again->vertices, zoo[i].mesh.vertices);
  }
  EXPECT_EQ(count.size(), 5u);
  EXPECT_NE(zoo[0].seed, zoo[1].seed);
  EXPECT_TRUE(make_zoo(0, 5).empty());
}

TEST(Zoo, ShapesGivePaperStyleViews) {
  Expected<Mesh> m = make_zoo_shape("chair", 4);
  ASSERT_TRUE(m.ok());
  const Cloud full = mesh_vertices(*m);
  for (const Vec3& camera : paper_viewpoints(full.points)) {
    const Cloud view = hidden_point_removal(full.points, camera);
    EXPECT_GT(view.points.size(), full.points.size() / 10);
    EXPECT_LT(view.points.size(), full.points.size());
  }
}

}  // namespace
}  // namespace glimpse

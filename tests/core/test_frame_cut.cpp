// Objects cut by the camera's frame: a person-sized box seen from 0.8 m reaches the image's top and
// bottom, from 4 m it does not; the frame turns with the cloud, lasts a stream while the sensor stays,
// and keeps a cut part from being "too small".
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "glimpse/geometry/frame_cut.h"
#include "glimpse/learning/model.h"
#include "glimpse/views/placement.h"
#include "glimpse/views/sensors.h"

namespace glimpse {
namespace {

// A closed box sx x sy x sz standing on z = 0, centred on the z axis.
Mesh box(float sx, float sy, float sz) {
  Mesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back((i & 1 ? 0.5f : -0.5f) * sx, (i & 2 ? 0.5f : -0.5f) * sy, i & 4 ? sz : 0.f);
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) m.faces.emplace_back(q[0], q[1], q[2]), m.faces.emplace_back(q[0], q[2], q[3]);
  return m;
}

// A person-sized box seen level from `distance_m` (to its centre) by a noiseless depth camera.
Cloud person_seen_from(float distance_m) {
  auto scene = RayScene::build(box(0.35f, 0.25f, 1.7f));
  EXPECT_TRUE(scene.ok());
  DepthCameraParams p;
  p.noise_a_m = p.noise_b_per_m = 0, p.disparity_step_px = 0;
  return depth_camera_scan(*scene, orbit_pose(Vec3(0, 0, 0.85f), 0, 0, distance_m), p, 1);
}

TEST(FrameCut, APersonSeenFromCloseByReachesTheTopAndBottomOfTheImage) {
  const Cloud close = person_seen_from(0.8f);
  ASSERT_TRUE(close.frame.has_value());
  ASSERT_GT(close.points.size(), 1000u);
  const FrameCut cut = frame_cut(close);
  EXPECT_TRUE(cut.top);
  EXPECT_TRUE(cut.bottom);
  EXPECT_FALSE(cut.left);  // 0.35 m wide: inside the 57 degrees
  EXPECT_FALSE(cut.right);
  EXPECT_EQ(describe(cut), "top, bottom");
  EXPECT_EQ(frame_edges(cut), (std::vector<std::string>{"top", "bottom"}));

  const Cloud far = person_seen_from(4.f);
  ASSERT_GT(far.points.size(), 100u);
  const FrameCut whole = frame_cut(far);
  EXPECT_FALSE(whole.any());
  EXPECT_EQ(describe(whole), "");
}

TEST(FrameCut, NothingIsCutWithoutAFrameASensorOrAFieldOfView) {
  Cloud close = person_seen_from(0.8f);
  Cloud no_frame = close;
  no_frame.frame.reset();
  EXPECT_FALSE(frame_cut(no_frame).any());
  Cloud no_sensor = close;
  no_sensor.sensor.reset();
  EXPECT_FALSE(frame_cut(no_sensor).any());
  Cloud no_fov = close;
  no_fov.frame->fov_v_deg = 0;
  EXPECT_FALSE(frame_cut(no_fov).any());
}

TEST(FrameCut, TheFrameTurnsWithTheCloud) {
  const Cloud close = person_seen_from(0.8f);
  const Eigen::Matrix3f turn = Eigen::AngleAxisf(1.1f, Vec3::UnitZ()).toRotationMatrix();
  const Cloud turned = rotate_about_centroid(close, turn);
  ASSERT_TRUE(turned.frame.has_value());
  EXPECT_TRUE(turned.frame->axis.isApprox(turn * close.frame->axis));
  const FrameCut a = frame_cut(close), b = frame_cut(turned);
  EXPECT_EQ(describe(a), describe(b));
}

TEST(FrameCut, AStreamKeepsItsFrameOnlyWhileTheSensorStays) {
  const Cloud close = person_seen_from(0.8f);
  Cloud scan;
  Cloud chunk{{close.points[0]}, close.sensor, close.frame};
  scan.frame = joined_frame(scan, chunk, true);
  scan.sensor = chunk.sensor;
  EXPECT_TRUE(scan.frame.has_value());
  EXPECT_TRUE(joined_frame(scan, chunk, false).has_value());  // the same view, streamed
  Cloud moved = chunk;
  moved.sensor = *chunk.sensor + Vec3(0.5f, 0, 0);
  EXPECT_FALSE(joined_frame(scan, moved, false).has_value());
  Cloud other_frame = chunk;
  other_frame.frame->fov_h_deg = 70;
  EXPECT_FALSE(joined_frame(scan, other_frame, false).has_value());
}

TEST(FrameCut, APartTheFrameCutsIsNeverTooSmall) {
  const Cloud close = person_seen_from(0.8f);  // about 0.63 m of a 1.7 m box
  TrainingSummary stats;
  stats.min_extent_m = 4, stats.max_extent_m = 8;
  Cloud unframed = close;
  unframed.frame.reset();
  EXPECT_NE(size_warning(stats, unframed).find("spans only"), std::string::npos);
  EXPECT_EQ(size_warning(stats, close), "");
  stats.min_extent_m = 0.01f, stats.max_extent_m = 0.1f;  // far too large stays a warning, cut or not
  EXPECT_NE(size_warning(stats, close).find("another unit"), std::string::npos);
}

}  // namespace
}  // namespace glimpse

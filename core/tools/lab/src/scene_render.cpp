// Synthetic scenes: objects placed on a floor in front of a wall (free-standing, touching or behind one
// another), one combined mesh cast by the depth camera, and each frame point labelled with its object by
// casting its ray against every object alone.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "glimpse/lab/scenes.h"
#include "glimpse/views/placement.h"

namespace glimpse {

namespace {

using Rng = std::mt19937_64;

float uniform(Rng& rng, float lo, float hi) { return lo < hi ? std::uniform_real_distribution<float>(lo, hi)(rng) : lo; }

void append(Mesh& into, const Mesh& mesh) {
  const int offset = int(into.vertices.size());
  into.vertices.insert(into.vertices.end(), mesh.vertices.begin(), mesh.vertices.end());
  for (const Eigen::Vector3i& f : mesh.faces) into.faces.push_back(f + Eigen::Vector3i::Constant(offset));
}

// The rectangle a, b, c, d (in order round it) as two triangles.
Mesh quad(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return Mesh{{a, b, c, d}, {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3)}};
}

// The pool object as a scene shows it: turned about +z by a random yaw (a random pose when it has no
// natural up), centred on the origin, on the floor.
Mesh posed(const EvalObject& object, Rng& rng) {
  Eigen::Matrix3f turn;
  if (object.any_pose) turn = random_rotation(rng());
  else turn = Eigen::AngleAxisf(uniform(rng, 0.f, 2 * std::numbers::pi_v<float>), Vec3::UnitZ()).toRotationMatrix();
  Mesh mesh = object.mesh;
  for (Vec3& v : mesh.vertices) v = turn * v;
  return place_on_ground(std::move(mesh));
}

Bounds shifted(const Bounds& b, const Vec3& shift) { return {b.min + shift, b.max + shift}; }

// Where a box `b` (centred on the origin) might stand, arranged as `how` against `anchor`: the shift of
// its box. Touching: 0-max_touch_gap_m beside one of the anchor's four sides, overlapping it along that
// side. Behind: further from the camera (+y) than the anchor, overlapping it across the view.
Vec3 candidate(const Bounds& b, Arrangement how, const Bounds& anchor, const Bounds& first, const SceneLayout& L, Rng& rng) {
  const Vec3 a = anchor.extent(), e = b.extent(), c = anchor.centre() - b.centre();
  if (how == Arrangement::kTouching) {
    const float gap = uniform(rng, 0.f, L.max_touch_gap_m);
    const int side = int(rng() % 4);
    const int axis = side / 2, across = 1 - axis;
    Vec3 s(c.x(), c.y(), 0.f);
    s[across] += uniform(rng, -0.4f, 0.4f) * (a[across] + e[across]);
    s[axis] = side % 2 ? anchor.max[axis] + gap - b.min[axis] : anchor.min[axis] - gap - b.max[axis];
    return s;
  }
  if (how == Arrangement::kBehind) {
    const float gap = uniform(rng, L.min_behind_gap_m, L.max_behind_gap_m);
    return Vec3(c.x() + uniform(rng, -0.3f, 0.3f) * (a.x() + e.x()), anchor.max.y() + gap - b.min.y(), 0.f);
  }
  const Vec3 f = first.centre() - b.centre();
  return Vec3(f.x() + uniform(rng, -L.spread_m, L.spread_m), f.y() + uniform(rng, -L.spread_m, L.spread_m), 0.f);
}

// A candidate stands apart from every placed box but its anchor (free-standing: free_gap_m apart).
bool fits(const Bounds& box, const std::vector<PlacedObject>& placed, Arrangement how, int anchor, const SceneLayout& L) {
  for (size_t k = 0; k < placed.size(); ++k) {
    if (int(k) == anchor && how == Arrangement::kTouching) continue;
    const float gap = box_gap(box, placed[k].box);
    if (how == Arrangement::kFree ? gap < L.free_gap_m : !(gap > 0.f)) return false;
  }
  return true;
}

// Places `mesh` among `placed`: the arrangement drawn, else free-standing; false when nothing fits.
bool place(Mesh mesh, size_t pool_index, std::vector<PlacedObject>& placed, const SceneLayout& L, Rng& rng) {
  const Bounds b = bounds(mesh.vertices);
  Arrangement how = Arrangement::kFree;
  int anchor = -1;
  if (!placed.empty()) {
    const double draw = std::uniform_real_distribution<double>(0, 1)(rng);
    how = draw < L.touching_chance ? Arrangement::kTouching
          : draw < L.touching_chance + L.behind_chance ? Arrangement::kBehind : Arrangement::kFree;
    if (how != Arrangement::kFree) anchor = int(rng() % placed.size());
  }
  for (int attempt = 0; attempt < 60; ++attempt) {
    if (attempt == 30) how = Arrangement::kFree, anchor = -1;
    const Bounds& next_to = anchor >= 0 ? placed[size_t(anchor)].box : b;
    const Vec3 shift = placed.empty() ? Vec3::Zero() : candidate(b, how, next_to, placed.front().box, L, rng);
    const Bounds box = shifted(b, shift);
    if (!fits(box, placed, how, anchor, L)) continue;
    for (Vec3& v : mesh.vertices) v += shift;
    placed.push_back({pool_index, std::move(mesh), box, how, anchor});
    return true;
  }
  return false;
}

// The floor from in front of the group to the wall, and the wall behind the group (+y), room_half_m either
// side of it.
void build_room(RoomScene& scene, const Bounds& group, const SceneLayout& L) {
  const float h = L.room_half_m, wall_y = group.max.y() + L.wall_gap_m;
  const float x0 = group.centre().x() - h, x1 = group.centre().x() + h, y0 = group.centre().y() - h;
  scene.floor = quad({x0, y0, 0}, {x1, y0, 0}, {x1, wall_y, 0}, {x0, wall_y, 0});
  scene.room = scene.floor;
  append(scene.room, quad({x0, wall_y, 0}, {x1, wall_y, 0}, {x1, wall_y, L.wall_height_m}, {x0, wall_y, L.wall_height_m}));
}

// The camera in front of the group, looking at its box's centre from min_down_deg-max_down_deg above.
SensorPose camera_pose(const Bounds& group, const SceneLayout& L, Rng& rng) {
  const float distance = uniform(rng, L.min_distance_m, L.max_distance_m);
  const float elevation = uniform(rng, L.min_down_deg, L.max_down_deg);
  const float azimuth = -90.f + uniform(rng, -L.max_azimuth_deg, L.max_azimuth_deg);
  return orbit_pose(group.centre(), azimuth, elevation, distance);
}

// Whether the ray o + t d (t in (0, t_max]) passes through box `b` (slab test).
bool ray_meets_box(const Vec3& o, const Vec3& d, float t_max, const Bounds& b) {
  float t0 = 0.f, t1 = t_max;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.f) {
      if (o[a] < b.min[a] || o[a] > b.max[a]) return false;
      continue;
    }
    float ta = (b.min[a] - o[a]) / d[a], tb = (b.max[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

// One object seen alone on the scene's floor from the scene's pose: its points (the floor's dropped).
Expected<Cloud> seen_alone(const RoomScene& scene, size_t k, const RayScene& object, const RayScene& floor,
                           const SceneLayout& layout) {
  Mesh with_floor = scene.floor;
  append(with_floor, scene.objects[k].mesh);
  auto cast = RayScene::build(with_floor);
  if (!cast.ok()) return cast.error();
  Cloud view = depth_camera_scan(*cast, scene.pose, layout.camera, scene.seed ^ (0x5bd1e995ull * (k + 1)));
  const std::vector<int> labels = label_points(view, {&object}, floor);
  Cloud alone{{}, view.sensor, view.frame};
  for (size_t i = 0; i < labels.size(); ++i)
    if (labels[i] == 0) alone.points.push_back(view.points[i]);
  return alone;
}

}  // namespace

float box_gap(const Bounds& a, const Bounds& b) {
  Vec3 gap;
  for (int k = 0; k < 3; ++k) gap[k] = std::max({0.f, b.min[k] - a.max[k], a.min[k] - b.max[k]});
  return gap.norm();
}

Expected<RoomScene> make_room_scene(const std::vector<EvalObject>& pool, const SceneLayout& layout, uint64_t seed) {
  if (pool.empty()) return invalid_argument("scenes: no object to place");
  if (layout.max_objects == 0 || layout.min_objects > layout.max_objects)
    return invalid_argument("scenes: want 1 <= min_objects <= max_objects");
  Rng rng(seed);
  RoomScene scene;
  scene.seed = seed;
  const size_t count = layout.min_objects + size_t(rng() % (layout.max_objects - layout.min_objects + 1));
  for (size_t k = 0; k < count; ++k) {
    const size_t pick = size_t(rng() % pool.size());
    place(posed(pool[pick], rng), pick, scene.objects, layout, rng);
  }
  Bounds group = scene.objects.front().box;
  for (const PlacedObject& o : scene.objects)
    group = {group.min.cwiseMin(o.box.min), group.max.cwiseMax(o.box.max)};
  build_room(scene, group, layout);
  scene.pose = camera_pose(group, layout, rng);
  Mesh all = scene.room;
  for (const PlacedObject& o : scene.objects) append(all, o.mesh);
  auto cast = RayScene::build(all);
  if (!cast.ok()) return Error{cast.error().code, "scenes: " + cast.error().message};
  scene.frame = depth_camera_scan(*cast, scene.pose, layout.camera, rng());
  return scene;
}

std::vector<int> label_points(const Cloud& frame, const std::vector<const RayScene*>& objects, const RayScene& room) {
  std::vector<int> labels(frame.points.size(), -1);
  const Vec3 sensor = frame.sensor.value_or(Vec3::Zero());
  for (size_t i = 0; i < frame.points.size(); ++i) {
    const Vec3 ray = frame.points[i] - sensor;
    if (!(ray.norm() > 0.f)) continue;
    const Vec3 dir = ray.normalized();
    const float reach = 2.f * ray.norm() + 1.f;  // past the point's own depth noise
    float nearest = std::numeric_limits<float>::infinity();
    for (size_t k = 0; k < objects.size(); ++k) {
      if (!ray_meets_box(sensor, dir, reach, objects[k]->scene_bounds())) continue;
      const RayScene::Hit hit = objects[k]->cast(sensor, dir, reach);
      if (hit.hit && hit.distance < nearest) nearest = hit.distance, labels[i] = int(k);
    }
    if (labels[i] < 0) continue;
    const RayScene::Hit wall = room.cast(sensor, dir, reach);
    if (wall.hit && wall.distance <= nearest) labels[i] = -1;
  }
  return labels;
}

const char* scene_kind_name(SceneKind kind) {
  switch (kind) {
    case SceneKind::kFree: return "free-standing";
    case SceneKind::kTouching: return "touching";
    case SceneKind::kOccluded: return "occluded";
  }
  return "?";
}

Expected<std::vector<ObjectView>> scene_truth(const RoomScene& scene, const SceneLayout& layout) {
  std::vector<RayScene> objects;
  for (const PlacedObject& o : scene.objects) {
    auto cast = RayScene::build(o.mesh);
    if (!cast.ok()) return cast.error();
    objects.push_back(std::move(*cast));
  }
  auto room = RayScene::build(scene.room);
  auto floor = RayScene::build(scene.floor);
  if (!room.ok() || !floor.ok()) return invalid_argument("scenes: the room has no surface");
  std::vector<const RayScene*> pointers;
  for (const RayScene& s : objects) pointers.push_back(&s);
  const std::vector<int> labels = label_points(scene.frame, pointers, *room);
  std::vector<ObjectView> out(scene.objects.size());
  for (uint32_t i = 0; i < labels.size(); ++i)
    if (labels[i] >= 0) out[size_t(labels[i])].indices.push_back(i);
  for (size_t k = 0; k < out.size(); ++k) {
    ObjectView& v = out[k];
    Points points;
    for (uint32_t i : v.indices) points.push_back(scene.frame.points[i]);
    v.box = bounds(points);
    auto alone = seen_alone(scene, k, objects[k], *floor, layout);
    if (!alone.ok()) return alone.error();
    v.alone = std::move(*alone);
    v.alone_points = v.alone.points.size();
    v.visible = v.alone_points ? double(v.indices.size()) / double(v.alone_points) : 0.0;
    for (size_t j = 0; j < out.size(); ++j)
      v.touching |= j != k && box_gap(scene.objects[k].box, scene.objects[j].box) <= layout.max_touch_gap_m + 1e-4f;
    v.occluded = v.alone_points > 0 && v.visible < 0.9;
    v.kind = v.touching ? SceneKind::kTouching : v.occluded ? SceneKind::kOccluded : SceneKind::kFree;
  }
  return out;
}

}  // namespace glimpse

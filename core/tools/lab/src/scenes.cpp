// Scoring synthetic scenes: segment_scene's objects matched to the true ones by 3-D box IoU, why a true
// object went unfound or a detection matched nothing, each matched object classified in the scene and
// alone, and the run's figures.
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <optional>

#include "glimpse/lab/scenes.h"
#include "glimpse/threads.h"
#include "glimpse/views/sampling.h"

namespace glimpse {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// body(i) for i in [0, n) on `threads` threads, each result in its own slot; progress from thread 0.
template <class Body>
void parallel_for(size_t n, int threads, const std::string& phase, const EvalProgressFn& progress, Body&& body) {
  std::atomic<size_t> done{0};
  if (progress) progress({phase, 0, n});
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int64_t i = 0; i < int64_t(n); ++i) {
    body(size_t(i));
    const size_t d = ++done;
    if (progress && omp_get_thread_num() == 0) progress({phase, d, n});
  }
  if (progress) progress({phase, n, n});
}

double volume(const Bounds& b) {
  const Vec3 e = (b.max - b.min).cwiseMax(Vec3::Zero());
  return double(e.x()) * double(e.y()) * double(e.z());
}

// Per frame point: the index of the detection holding it, or -1.
std::vector<int> detection_of_points(size_t points, const Scene& scene) {
  std::vector<int> of(points, -1);
  for (size_t d = 0; d < scene.objects.size(); ++d)
    for (uint32_t i : scene.objects[d].indices) of[i] = int(d);
  return of;
}

// How many of `indices` each detection (or -1: none) holds.
std::map<int, size_t> shares(const std::vector<uint32_t>& indices, const std::vector<int>& of) {
  std::map<int, size_t> n;
  for (uint32_t i : indices) ++n[of[i]];
  return n;
}

// The owner (a true object's index, -1 the room) of most of a detection's points beside `except`, and
// how many points it has there.
std::pair<int, size_t> main_owner(const SceneObject& detection, const std::vector<int>& truth_of, int except) {
  std::map<int, size_t> n;
  for (uint32_t i : detection.indices)
    if (truth_of[i] != except) ++n[truth_of[i]];
  std::pair<int, size_t> best{-1, 0};
  for (const auto& [owner, count] : n)
    if (count > best.second) best = {owner, count};
  return best;
}

struct SceneData {
  const RoomScene& room;
  const std::vector<ObjectView>& truth;
  const Scene& scene;
  const std::vector<EvalObject>& pool;
  const ScenesParams& params;
  std::vector<int> truth_of, detection_of;  // per frame point
  std::optional<Scene> relaxed{};           // segment_scene without its size rules, when a miss needs it

  const std::string& category(int t) const { return pool[room.objects[size_t(t)].pool_index].category; }
  std::string owner_name(int t) const { return t < 0 ? std::string("the room") : category(t); }
};

// Why true object t, whose points are mostly in no detection, was lost: dropped by the size rules (found
// when they are lifted), in a removed plane, or scattered.
std::string lost_reason(SceneData& s, int t) {
  const ObjectView& v = s.truth[size_t(t)];
  if (!s.relaxed) {
    SceneParams relaxed = s.params.segmentation;
    relaxed.max_object_extent_m = std::numeric_limits<float>::infinity();
    relaxed.max_object_points = std::numeric_limits<size_t>::max();
    relaxed.max_objects = std::numeric_limits<size_t>::max();
    auto again = segment_scene(s.room.frame, relaxed);
    s.relaxed = again.ok() ? std::move(*again) : Scene{};
  }
  const std::vector<int> of = detection_of_points(s.room.frame.points.size(), *s.relaxed);
  for (const auto& [d, n] : shares(v.indices, of)) {
    if (d < 0 || 2 * n < v.indices.size()) continue;
    const SceneObject& o = s.relaxed->objects[size_t(d)];
    const float extent = (o.box_max - o.box_min).maxCoeff();
    if (extent > s.params.segmentation.max_object_extent_m)
      return "dropped by the extent rule (" + std::to_string(int(std::lround(extent * 100))) + " cm)";
    return "dropped by the size rules";
  }
  size_t in_plane = 0;
  for (uint32_t i : v.indices)
    for (const Plane& p : s.scene.planes)
      if (std::abs(p.normal.dot(s.room.frame.points[i]) + p.offset) <=
          plane_reach(s.room.frame.points[i], s.room.frame.sensor.value_or(Vec3::Zero()), s.params.segmentation)) {
        ++in_plane;
        break;
      }
  return 2 * in_plane >= v.indices.size() ? "in a removed plane" : "scattered";
}

// Why true object t matched no detection.
std::string miss_reason(SceneData& s, int t) {
  const ObjectView& v = s.truth[size_t(t)];
  if (v.indices.size() < s.scene.min_object_points) return "too few points";
  const std::map<int, size_t> n = shares(v.indices, s.detection_of);
  std::pair<int, size_t> best{-1, 0};
  size_t pieces = 0, in_pieces = 0;
  for (const auto& [d, count] : n) {
    if (d >= 0 && count > best.second) best = {d, count};
    if (d >= 0 && 10 * count >= v.indices.size()) ++pieces, in_pieces += count;
  }
  if (best.first >= 0 && 2 * best.second >= v.indices.size()) {
    const SceneObject& d = s.scene.objects[size_t(best.first)];
    if (double(best.second) < 0.6 * double(d.indices.size()))
      return "merged with " + s.owner_name(main_owner(d, s.truth_of, t).first);
    // How much of the object the detection holds, and how much of the detection is something else.
    auto percent = [](double share) { return std::to_string(int(std::lround(100 * share))) + " %"; };
    return "box off (" + percent(double(best.second) / double(v.indices.size())) + " of it; " +
           percent(1 - double(best.second) / double(d.indices.size())) + " else)";
  }
  if (pieces >= 2 && 2 * in_pieces >= v.indices.size()) return "split in " + std::to_string(pieces);
  return lost_reason(s, t);
}

// What an unmatched detection's points are: the room, two objects merged, or part of one.
std::string detection_origin(const SceneData& s, const SceneObject& d) {
  const auto [first, n1] = main_owner(d, s.truth_of, -2);
  if (first < 0) return "the room";
  const auto [second, n2] = main_owner(d, s.truth_of, first);
  if (second >= 0 && 5 * n2 >= d.indices.size()) return "merged " + s.category(first) + " + " + s.category(second);
  return "part of " + s.category(first);
}

SceneOutcome score(SceneData& s) {
  SceneOutcome out;
  out.seed = s.room.seed;
  out.pose = s.room.pose;
  out.frame_points = s.room.frame.points.size();
  out.planes = s.scene.planes.size();
  s.truth_of.assign(out.frame_points, -1);
  for (size_t t = 0; t < s.truth.size(); ++t)
    for (uint32_t i : s.truth[t].indices) s.truth_of[i] = int(t);
  s.detection_of = detection_of_points(out.frame_points, s.scene);
  std::vector<Bounds> detected, truth;
  for (const SceneObject& o : s.scene.objects) detected.push_back({o.box_min, o.box_max});
  for (const ObjectView& v : s.truth) truth.push_back(v.box);
  for (size_t t = 0; t < s.truth.size(); ++t) {
    const ObjectView& v = s.truth[t];
    const EvalObject& o = s.pool[s.room.objects[t].pool_index];
    TruthOutcome& x = out.truth.emplace_back();
    x.category = o.category, x.id = o.id, x.source = o.source;
    x.kind = v.kind, x.touching = v.touching, x.occluded = v.occluded;
    x.visible = v.visible, x.points = v.indices.size(), x.extent = v.box.extent();
    Vec3 sum = Vec3::Zero();
    for (uint32_t i : v.indices) sum += s.room.frame.points[i];
    if (!v.indices.empty()) x.range_m = (sum / float(v.indices.size()) - s.room.pose.position).norm();
  }
  for (size_t d = 0; d < detected.size(); ++d) {
    DetectionOutcome& x = out.detections.emplace_back();
    x.box = detected[d], x.points = s.scene.objects[d].indices.size(), x.range_m = s.scene.objects[d].range_m;
  }
  for (const BoxMatch& m : match_boxes(detected, truth, s.params.min_iou)) {
    out.truth[size_t(m.truth)].detection = m.detection, out.truth[size_t(m.truth)].iou = m.iou;
    out.detections[size_t(m.detection)].truth = m.truth;
  }
  for (size_t t = 0; t < out.truth.size(); ++t)
    if (out.truth[t].detection < 0 && out.truth[t].visible >= s.params.min_visible) out.truth[t].miss = miss_reason(s, int(t));
  for (size_t d = 0; d < out.detections.size(); ++d)
    if (out.detections[d].truth < 0) out.detections[d].origin = detection_origin(s, s.scene.objects[d]);
  return out;
}

Verdict verdict_of(const Model& model, const Cloud& cloud) {
  Verdict v;
  v.points = cloud.points.size();
  auto c = classify(model, cloud);
  if (!c.ok() || c->winner < 0) return v;
  v.decided = true;
  v.winner = c->categories[size_t(c->winner)];
  v.unknown = c->unknown;
  return v;
}

}  // namespace

SceneOutcome score_scene(const RoomScene& room, const std::vector<ObjectView>& truth, const Scene& segmented,
                         const std::vector<EvalObject>& pool, const ScenesParams& params) {
  SceneData s{room, truth, segmented, pool, params, {}, {}};
  return score(s);
}

double box_iou(const Bounds& a, const Bounds& b) {
  if (a.min == b.min && a.max == b.max) return 1.0;
  const Bounds both{a.min.cwiseMax(b.min), a.max.cwiseMin(b.max)};
  if ((both.max - both.min).minCoeff() < 0) return 0.0;
  const double inter = volume(both), uni = volume(a) + volume(b) - inter;
  return uni > 0 ? inter / uni : 0.0;
}

std::vector<BoxMatch> match_boxes(const std::vector<Bounds>& detections, const std::vector<Bounds>& truth, double min_iou) {
  std::vector<BoxMatch> pairs;
  for (size_t d = 0; d < detections.size(); ++d)
    for (size_t t = 0; t < truth.size(); ++t)
      if (const double iou = box_iou(detections[d], truth[t]); iou >= min_iou) pairs.push_back({int(d), int(t), iou});
  std::stable_sort(pairs.begin(), pairs.end(), [](const BoxMatch& a, const BoxMatch& b) { return a.iou > b.iou; });
  std::vector<char> used_d(detections.size(), 0), used_t(truth.size(), 0);
  std::vector<BoxMatch> out;
  for (const BoxMatch& p : pairs) {
    if (used_d[size_t(p.detection)] || used_t[size_t(p.truth)]) continue;
    used_d[size_t(p.detection)] = used_t[size_t(p.truth)] = 1;
    out.push_back(p);
  }
  return out;
}

Expected<ScenesResult> run_scenes(const std::vector<EvalObject>& pool, const Model* model, const ScenesParams& params,
                                  const EvalProgressFn& progress) {
  if (pool.empty()) return invalid_argument("scenes: no object to place");
  if (params.scenes == 0) return invalid_argument("scenes: want at least one scene");
  const auto t_start = Clock::now();
  ScenesResult r;
  r.params = params;
  r.threads = resolve_threads(params.threads);
  if (model) r.categories = model->categories;
  const size_t n = params.scenes;
  std::vector<std::optional<RoomScene>> rooms(n);
  std::vector<std::vector<ObjectView>> truths(n);
  std::vector<std::optional<Error>> failed(n);
  auto t0 = Clock::now();
  parallel_for(n, r.threads, "make and label scenes", progress, [&](size_t i) {
    auto room = make_room_scene(pool, params.layout, object_seed(params.seed, "scene/" + std::to_string(i)));
    if (!room.ok()) {
      failed[i] = room.error();
      return;
    }
    auto truth = scene_truth(*room, params.layout);
    if (!truth.ok()) {
      failed[i] = truth.error();
      return;
    }
    rooms[i] = std::move(*room), truths[i] = std::move(*truth);
  });
  for (const auto& e : failed)
    if (e) return *e;
  r.timings.push_back({"make and label scenes", seconds_since(t0), std::to_string(n) + " scenes"});
  t0 = Clock::now();
  std::vector<Scene> segmented(n);
  r.scenes.resize(n);
  for (size_t i = 0; i < n; ++i) {  // one frame at a time: the time is segment_scene's alone
    if (progress) progress({"segment scenes", i, n});
    const auto t_frame = Clock::now();
    auto scene = segment_scene(rooms[i]->frame, params.segmentation);
    r.scenes[i].segment_ms = 1000 * seconds_since(t_frame);
    if (!scene.ok()) return Error{scene.error().code, "segment_scene: " + scene.error().message};
    segmented[i] = std::move(*scene);
  }
  r.timings.push_back({"segment scenes", seconds_since(t0), "one frame at a time"});
  t0 = Clock::now();
  parallel_for(n, r.threads, "match", progress, [&](size_t i) {
    const double ms = r.scenes[i].segment_ms;
    r.scenes[i] = score_scene(*rooms[i], truths[i], segmented[i], pool, params);
    r.scenes[i].segment_ms = ms;
  });
  r.timings.push_back({"match", seconds_since(t0), ""});
  if (!model) {
    r.total_seconds = seconds_since(t_start);
    return r;
  }
  std::vector<std::pair<size_t, size_t>> items;  // (scene, true object) to classify
  for (size_t i = 0; i < n; ++i)
    for (size_t t = 0; t < r.scenes[i].truth.size(); ++t)
      if (r.scenes[i].truth[t].detection >= 0 && r.scenes[i].truth[t].visible >= params.min_visible) items.push_back({i, t});
  t0 = Clock::now();
  parallel_for(items.size(), r.threads, "classify", progress, [&](size_t k) {
    const auto [i, t] = items[k];
    TruthOutcome& o = r.scenes[i].truth[t];
    o.scene = verdict_of(*model, object_cloud(rooms[i]->frame, segmented[i].objects[size_t(o.detection)]));
    o.alone = verdict_of(*model, truths[i][t].alone);
  });
  r.timings.push_back({"classify", seconds_since(t0), std::to_string(2 * items.size()) + " clouds (in the scene, alone)"});
  r.total_seconds = seconds_since(t_start);
  return r;
}

ScenesSummary summarise(const ScenesResult& r) {
  ScenesSummary s;
  std::vector<double> ms;
  for (const SceneOutcome& scene : r.scenes) {
    ms.push_back(scene.segment_ms);
    for (const TruthOutcome& t : scene.truth) {
      ++s.objects;
      if (t.visible < r.params.min_visible) continue;
      ++s.visible_objects;
      const bool found = t.detection >= 0;
      ++s.recall.total, s.recall.correct += found;
      ++s.recall_by_kind[size_t(t.kind)].total, s.recall_by_kind[size_t(t.kind)].correct += found;
      if (!t.scene.decided && !t.alone.decided) continue;
      const bool scene_right = t.scene.decided && t.scene.winner == t.category;
      const bool alone_right = t.alone.decided && t.alone.winner == t.category;
      ++s.scene_closest.total, s.scene_closest.correct += scene_right;
      ++s.scene_accepted.total, s.scene_accepted.correct += scene_right && !t.scene.unknown;
      ++s.alone_closest.total, s.alone_closest.correct += alone_right;
      ++s.alone_accepted.total, s.alone_accepted.correct += alone_right && !t.alone.unknown;
      s.scene_unknown += t.scene.decided && t.scene.unknown;
      s.alone_unknown += t.alone.decided && t.alone.unknown;
    }
    for (const DetectionOutcome& d : scene.detections) {
      ++s.detections;
      if (d.truth >= 0 && scene.truth[size_t(d.truth)].visible < r.params.min_visible) {
        ++s.ignored_detections;
        continue;
      }
      ++s.precision.total, s.precision.correct += d.truth >= 0;
    }
  }
  if (!ms.empty()) {
    std::sort(ms.begin(), ms.end());
    s.median_segment_ms = ms.size() % 2 ? ms[ms.size() / 2] : 0.5 * (ms[ms.size() / 2 - 1] + ms[ms.size() / 2]);
    s.max_segment_ms = ms.back();
  }
  return s;
}

}  // namespace glimpse

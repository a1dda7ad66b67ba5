// The scenes run's report: report.md (detection, why objects went unfound, recognition in the scene beside
// alone, the segmentation's parameters and time), scenes.json (the figures and every scene) and
// objects.csv (every true object).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "glimpse/lab/scenes.h"
#include "report_format.h"

namespace glimpse {

using eval_internal::fmt;

namespace {

// The Wilson score interval holding the proportion with 95 % confidence, in %.
std::pair<double, double> wilson(const Tally& t) {
  if (t.total == 0) return {NAN, NAN};
  const double z = 1.96, n = double(t.total), p = double(t.correct) / n;
  const double centre = (p + z * z / (2 * n)) / (1 + z * z / n);
  const double half = z * std::sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n);
  return {100 * (centre - half), 100 * (centre + half)};
}

// "95.2 % (100 / 105; 89.3-98.0)".
std::string rate(const Tally& t) {
  if (t.total == 0) return "–";
  const auto [low, high] = wilson(t);
  return fmt("%.1f %%", t.percent()) + " (" + std::to_string(t.correct) + " / " + std::to_string(t.total) + "; " +
         fmt("%.1f", low) + "-" + fmt("%.1f", high) + ")";
}

std::string points_of(double difference) { return fmt("%+.1f", difference); }

std::string detection_section(const ScenesResult& r, const ScenesSummary& s) {
  std::ostringstream o;
  o << "## Detection\n\nA detection is right when its box overlaps a true object's box (the box of the frame points "
       "whose rays reach that object first) with IoU >= "
    << fmt("%.2f", r.params.min_iou) << ", one to one, the highest IoU first. Recall is over the true objects at least "
    << fmt("%.0f", 100 * r.params.min_visible) << " % visible (of what the same camera sees of them alone on the floor); "
    << "a detection of an object less visible is neither right nor wrong (" << s.ignored_detections
    << " such). In brackets: found / total and the 95 % Wilson interval.\n\n"
    << "| figure | value | target |\n|---|---|---|\n"
    << "| recall | " << rate(s.recall) << " | >= 95 % |\n"
    << "| precision | " << rate(s.precision) << " | >= 95 % |\n";
  for (SceneKind k : {SceneKind::kFree, SceneKind::kTouching, SceneKind::kOccluded})
    o << "| recall, " << scene_kind_name(k) << " | " << rate(s.recall_by_kind[size_t(k)]) << " | |\n";
  o << "\nKinds: **touching** objects' mesh boxes are at most " << fmt("%.0f", 100 * r.params.layout.max_touch_gap_m)
    << " cm from another's; **occluded** ones (not touching) have at least 10 % of what the camera sees of them alone "
       "hidden by other objects; the rest are **free-standing**.\n\n";
  Tally bins[3], ranges[3];
  size_t unmatched[3] = {0, 0, 0};
  auto range_bin = [](float m) { return m < 2.5f ? 0 : m < 3.5f ? 1 : 2; };
  for (const SceneOutcome& scene : r.scenes) {
    for (const TruthOutcome& t : scene.truth) {
      if (t.visible < r.params.min_visible) continue;
      for (Tally* bin : {&bins[t.visible < 0.6 ? 0 : t.visible < 0.9 ? 1 : 2], &ranges[range_bin(t.range_m)]})
        ++bin->total, bin->correct += t.detection >= 0;
    }
    for (const DetectionOutcome& d : scene.detections) unmatched[range_bin(d.range_m)] += d.truth < 0;
  }
  o << "| visible | recall |\n|---|---|\n| " << fmt("%.0f", 100 * r.params.min_visible) << "-60 % | " << rate(bins[0])
    << " |\n| 60-90 % | " << rate(bins[1]) << " |\n| 90 % and more | " << rate(bins[2]) << " |\n\n";
  const char* range_names[] = {"under 2.5 m", "2.5-3.5 m", "3.5 m and more"};
  o << "By the range of an object's (or a detection's) centroid from the camera; the depth camera's noise and "
       "disparity steps grow with the square of the range (3.5 cm steps at 3.5 m):\n\n"
    << "| range | recall | unmatched detections |\n|---|---|---:|\n";
  for (int k = 0; k < 3; ++k) o << "| " << range_names[k] << " | " << rate(ranges[k]) << " | " << unmatched[k] << " |\n";
  o << "\n";
  return o.str();
}

// Counts of each reason (true objects unfound, or unmatched detections), largest first.
std::string reason_table(const std::map<std::string, size_t>& counts, const char* head) {
  std::vector<std::pair<size_t, std::string>> rows;
  for (const auto& [reason, n] : counts) rows.push_back({n, reason});
  std::sort(rows.begin(), rows.end(),
            [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
  std::ostringstream o;
  o << "| " << head << " | count |\n|---|---:|\n";
  for (const auto& [n, reason] : rows) o << "| " << reason << " | " << n << " |\n";
  if (rows.empty()) o << "| none | 0 |\n";
  return o.str();
}

// A miss's reason without its particulars: "split in 3" is "split", "merged with chair" "merged with
// another object", the extent rule's length and the box's shares dropped.
std::string reason_kind(const std::string& miss) {
  if (miss.rfind("split", 0) == 0) return "split";
  if (miss.rfind("box off", 0) == 0) return "box off";
  if (miss.rfind("dropped by the extent rule", 0) == 0) return "dropped by the extent rule";
  if (miss.rfind("merged with", 0) == 0 && miss != "merged with the room") return "merged with another object";
  return miss;
}

std::string failures_section(const ScenesResult& r) {
  std::map<std::string, size_t> misses, origins, missed_categories;
  for (const SceneOutcome& scene : r.scenes) {
    for (const TruthOutcome& t : scene.truth)
      if (!t.miss.empty()) ++misses[reason_kind(t.miss)], ++missed_categories[t.category + ", " + scene_kind_name(t.kind)];
    for (const DetectionOutcome& d : scene.detections)
      if (d.truth < 0) ++origins[d.origin];
  }
  std::ostringstream o;
  o << "## What limits detection\n\nEach unfound object (at least " << fmt("%.0f", 100 * r.params.min_visible)
    << " % visible) by what became of its points: *merged* (most of them in a detection mostly of another object), "
       "*split* (spread over detections), *box off* (most in one detection whose box still misses; objects.csv says how much of the object "
       "the detection holds and how much of it is something else), *dropped by the "
       "extent rule* or *the size rules* (found once segment_scene's max_object_extent_m and max_object_points are "
       "lifted), *in a removed plane*, *too few points* (under min_object_points).\n\n"
    << reason_table(misses, "why unfound") << "\n" << reason_table(missed_categories, "unfound: category, kind") << "\n"
    << "Detections that match no object, by what their points are:\n\n" << reason_table(origins, "unmatched detection")
    << "\nEvery object is listed in objects.csv (extent, visible share, kind, match, reason, answers).\n\n";
  return o.str();
}

std::string recognition_section(const ScenesResult& r, const ScenesSummary& s) {
  std::ostringstream o;
  o << "## Recognition in the scene and alone\n\nEvery matched object at least " << fmt("%.0f", 100 * r.params.min_visible)
    << " % visible, classified by the model's default method as the scene gives it (object_cloud of its detection) "
       "and as the same camera sees it alone on the floor from the same pose (its own points): the same objects. "
       "**Closest**: the winner is right, \"unknown\" ignored; **right and accepted**: right and not called unknown.\n\n"
    << "| figure | in the scene | alone | scene - alone (points) |\n|---|---|---|---:|\n"
    << "| closest | " << rate(s.scene_closest) << " | " << rate(s.alone_closest) << " | "
    << points_of(s.scene_closest.percent() - s.alone_closest.percent()) << " |\n"
    << "| right and accepted | " << rate(s.scene_accepted) << " | " << rate(s.alone_accepted) << " | "
    << points_of(s.scene_accepted.percent() - s.alone_accepted.percent()) << " |\n"
    << "| called unknown | " << s.scene_unknown << " of " << s.scene_closest.total << " | " << s.alone_unknown << " of "
    << s.alone_closest.total << " | |\n\nTarget: in the scene at most 3 points below alone.\n\n";
  std::map<std::string, std::array<Tally, 4>> by;  // scene closest, alone closest, scene accepted, alone accepted
  for (const SceneOutcome& scene : r.scenes)
    for (const TruthOutcome& t : scene.truth) {
      if (!t.scene.decided && !t.alone.decided) continue;
      auto& row = by[t.category];
      const bool sr = t.scene.winner == t.category, ar = t.alone.winner == t.category;
      for (Tally& x : row) ++x.total;
      row[0].correct += sr, row[1].correct += ar, row[2].correct += sr && !t.scene.unknown, row[3].correct += ar && !t.alone.unknown;
    }
  o << "| category | objects | closest, scene | closest, alone | accepted, scene | accepted, alone |\n|---|---:|---:|---:|---:|---:|\n";
  for (const auto& [category, row] : by)
    o << "| " << category << " | " << row[0].total << " | " << fmt("%.1f", row[0].percent()) << " | "
      << fmt("%.1f", row[1].percent()) << " | " << fmt("%.1f", row[2].percent()) << " | " << fmt("%.1f", row[3].percent()) << " |\n";
  return o.str() + "\n";
}

std::string settings_section(const ScenesResult& r, const ScenesSummary& s) {
  const SceneParams& p = r.params.segmentation;
  const SceneLayout& L = r.params.layout;
  std::ostringstream o;
  o << "## Segmentation and scenes\n\nsegment_scene per frame: median **" << fmt("%.1f", s.median_segment_ms)
    << " ms**, slowest " << fmt("%.1f", s.max_segment_ms) << " ms (one frame at a time, on a machine others share).\n\n"
    << "| segment_scene parameter | value |\n|---|---|\n"
    << "| voxel_m | " << p.voxel_m << " |\n| plane_distance_m | " << p.plane_distance_m << " |\n"
    << "| min_plane_fraction | " << p.min_plane_fraction << " |\n| min_plane_area_m2 | " << p.min_plane_area_m2 << " |\n"
    << "| max_planes | " << p.max_planes << " |\n| plane_fit_points | " << p.plane_fit_points << " |\n"
    << "| cluster_tolerance_m | " << p.cluster_tolerance_m << " |\n"
    << "| min_object_points | " << p.min_object_points << " |\n| reference_density_per_deg2 | " << p.reference_density_per_deg2
    << " |\n| max_object_points | " << p.max_object_points << " |\n"
    << "| max_object_extent_m | " << p.max_object_extent_m << " |\n| max_objects | " << p.max_objects << " |\n\n"
    << "Scenes: " << L.min_objects << "-" << L.max_objects << " objects each on a floor in front of a wall "
    << fmt("%.2f", L.wall_gap_m) << " m behind the farthest; after the first, each stands touching one before it ("
    << fmt("%.0f", 100 * L.touching_chance) << " %, boxes 0-" << fmt("%.0f", 100 * L.max_touch_gap_m) << " cm apart), behind one ("
    << fmt("%.0f", 100 * L.behind_chance) << " %, " << fmt("%.2f", L.min_behind_gap_m) << "-" << fmt("%.2f", L.max_behind_gap_m)
    << " m) or free (boxes at least " << fmt("%.2f", L.free_gap_m) << " m apart); objects without a natural up lie in a "
       "random pose, the others at a random yaw. The depth camera (" << L.camera.width << " x " << L.camera.height << ", "
    << L.camera.fov_h_deg << " x " << L.camera.fov_v_deg << " deg, Kinect noise and disparity steps) stands "
    << L.min_distance_m << "-" << L.max_distance_m << " m from the group's centre, " << L.min_down_deg << "-" << L.max_down_deg
    << " deg above it, within " << L.max_azimuth_deg << " deg of facing the wall, looking at the group.\n\n";
  return o.str();
}

std::string scenes_table(const ScenesResult& r) {
  std::ostringstream o;
  o << "## Scenes\n\n| scene | seed | objects | found / visible | detections | unmatched | planes | frame points | segment ms |\n"
    << "|---:|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (size_t i = 0; i < r.scenes.size(); ++i) {
    const SceneOutcome& s = r.scenes[i];
    size_t visible = 0, found = 0, unmatched = 0;
    for (const TruthOutcome& t : s.truth)
      if (t.visible >= r.params.min_visible) ++visible, found += t.detection >= 0;
    for (const DetectionOutcome& d : s.detections) unmatched += d.truth < 0;
    o << "| " << i << " | " << s.seed << " | " << s.truth.size() << " | " << found << " / " << visible << " | "
      << s.detections.size() << " | " << unmatched << " | " << s.planes << " | " << s.frame_points << " | "
      << fmt("%.1f", s.segment_ms) << " |\n";
  }
  return o.str();
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) >= 0x20) out += c;
  }
  return out + "\"";
}

std::string json_tally(const Tally& t) {
  return "{\"correct\": " + std::to_string(t.correct) + ", \"total\": " + std::to_string(t.total) +
         ", \"percent\": " + fmt("%.3f", t.percent()) + "}";
}

std::string json_vec(const Vec3& v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "[%.3f, %.3f, %.3f]", double(v.x()), double(v.y()), double(v.z()));
  return buf;
}

std::string json_params(const SceneParams& p) {
  std::ostringstream o;
  o << "{\"voxel_m\": " << p.voxel_m << ", \"plane_distance_m\": " << p.plane_distance_m << ", \"min_plane_fraction\": "
    << p.min_plane_fraction << ", \"min_plane_area_m2\": " << p.min_plane_area_m2 << ", \"max_planes\": " << p.max_planes
    << ", \"plane_fit_points\": " << p.plane_fit_points << ", \"cluster_tolerance_m\": " << p.cluster_tolerance_m
    << ", \"min_object_points\": " << p.min_object_points << ", \"max_object_points\": " << p.max_object_points
    << ", \"max_object_extent_m\": " << p.max_object_extent_m << ", \"max_objects\": " << p.max_objects << "}";
  return o.str();
}

std::string json_verdict(const Verdict& v) {
  return "{\"decided\": " + std::string(v.decided ? "true" : "false") + ", \"winner\": " + json_string(v.winner) +
         ", \"unknown\": " + (v.unknown ? "true" : "false") + ", \"points\": " + std::to_string(v.points) + "}";
}

}  // namespace

std::string scenes_markdown(const ScenesResult& r) {
  const ScenesSummary s = summarise(r);
  std::ostringstream o;
  o << "# Objects in synthetic scenes\n\n" << r.scenes.size() << " scenes (seed " << r.params.seed << ") of objects of "
    << r.tested_on << ", seen by a simulated depth camera and segmented by segment_scene; a model trained on "
    << r.trained_on << " recognises what it finds. " << s.objects << " objects placed, " << s.visible_objects
    << " of them at least " << fmt("%.0f", 100 * r.params.min_visible) << " % visible; " << s.detections
    << " detections. Segmentation parameters: " << r.tuned_on << ".\n\n";
  o << detection_section(r, s) << failures_section(r) << recognition_section(r, s) << settings_section(r, s);
  o << "## Time\n\n| phase | s | |\n|---|---:|---|\n";
  for (const PhaseTiming& t : r.timings) o << "| " << t.phase << " | " << fmt("%.1f", t.seconds) << " | " << t.detail << " |\n";
  o << "| total | " << fmt("%.1f", r.total_seconds) << " | " << r.threads << " threads |\n\n";
  return o.str() + scenes_table(r);
}

std::string scenes_json(const ScenesResult& r) {
  const ScenesSummary s = summarise(r);
  std::ostringstream o;
  o << "{\n  \"trained_on\": " << json_string(r.trained_on) << ",\n  \"tested_on\": " << json_string(r.tested_on)
    << ",\n  \"tuned_on\": " << json_string(r.tuned_on) << ",\n  \"seed\": " << r.params.seed << ",\n  \"scenes\": "
    << r.scenes.size() << ",\n  \"min_visible\": " << r.params.min_visible << ",\n  \"min_iou\": " << r.params.min_iou
    << ",\n  \"recall\": " << json_tally(s.recall) << ",\n  \"precision\": " << json_tally(s.precision)
    << ",\n  \"recall_by_kind\": {";
  for (size_t k = 0; k < 3; ++k)
    o << (k ? ", " : "") << json_string(scene_kind_name(SceneKind(k))) << ": " << json_tally(s.recall_by_kind[k]);
  o << "},\n  \"ignored_detections\": " << s.ignored_detections << ",\n  \"scene_closest\": " << json_tally(s.scene_closest)
    << ",\n  \"alone_closest\": " << json_tally(s.alone_closest) << ",\n  \"scene_accepted\": " << json_tally(s.scene_accepted)
    << ",\n  \"alone_accepted\": " << json_tally(s.alone_accepted) << ",\n  \"scene_unknown\": " << s.scene_unknown
    << ",\n  \"alone_unknown\": " << s.alone_unknown << ",\n  \"median_segment_ms\": " << fmt("%.3f", s.median_segment_ms)
    << ",\n  \"segmentation\": " << json_params(r.params.segmentation) << ",\n  \"frames\": [\n";
  for (size_t i = 0; i < r.scenes.size(); ++i) {
    const SceneOutcome& sc = r.scenes[i];
    o << "    {\"seed\": " << sc.seed << ", \"segment_ms\": " << fmt("%.3f", sc.segment_ms) << ", \"planes\": " << sc.planes
      << ", \"objects\": [";
    for (size_t t = 0; t < sc.truth.size(); ++t) {
      const TruthOutcome& x = sc.truth[t];
      o << (t ? ", " : "") << "{\"category\": " << json_string(x.category) << ", \"id\": " << json_string(x.source + ":" + x.id)
        << ", \"kind\": " << json_string(scene_kind_name(x.kind)) << ", \"visible\": " << fmt("%.4f", x.visible)
        << ", \"points\": " << x.points << ", \"range_m\": " << fmt("%.3f", x.range_m) << ", \"detection\": " << x.detection
        << ", \"iou\": " << fmt("%.4f", x.iou) << ", \"miss\": " << json_string(x.miss) << ", \"scene\": " << json_verdict(x.scene)
        << ", \"alone\": " << json_verdict(x.alone) << "}";
    }
    o << "], \"unmatched_detections\": [";
    bool first = true;
    for (const DetectionOutcome& d : sc.detections)
      if (d.truth < 0) {
        o << (first ? "" : ", ") << "{\"origin\": " << json_string(d.origin) << ", \"points\": " << d.points
          << ", \"range_m\": " << fmt("%.3f", d.range_m) << ", \"box\": [" << json_vec(d.box.min) << ", " << json_vec(d.box.max) << "]}";
        first = false;
      }
    o << "]}" << (i + 1 < r.scenes.size() ? "," : "") << "\n";
  }
  o << "  ]\n}\n";
  return o.str();
}

std::string scene_objects_csv(const ScenesResult& r) {
  std::ostringstream o;
  o << "scene,object,source,category,id,kind,touching,occluded,visible,points,range_m,extent_x,extent_y,extent_z,detection,iou,miss,"
       "scene_winner,scene_unknown,alone_winner,alone_unknown\n";
  for (size_t i = 0; i < r.scenes.size(); ++i)
    for (size_t t = 0; t < r.scenes[i].truth.size(); ++t) {
      const TruthOutcome& x = r.scenes[i].truth[t];
      o << i << "," << t << "," << x.source << "," << x.category << "," << x.id << "," << scene_kind_name(x.kind) << ","
        << int(x.touching) << "," << int(x.occluded) << "," << fmt("%.4f", x.visible) << "," << x.points << ","
        << fmt("%.3f", x.range_m) << "," << fmt("%.3f", x.extent.x()) << "," << fmt("%.3f", x.extent.y()) << ","
        << fmt("%.3f", x.extent.z()) << ","
        << x.detection << "," << fmt("%.3f", x.iou) << "," << x.miss << "," << x.scene.winner << "," << int(x.scene.unknown)
        << "," << x.alone.winner << "," << int(x.alone.unknown) << "\n";
    }
  return o.str();
}

Status write_scenes_report(const ScenesResult& r, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return invalid_argument("cannot create " + dir + ": " + ec.message());
  const std::pair<const char*, std::string> files[] = {
      {"report.md", scenes_markdown(r)}, {"scenes.json", scenes_json(r)}, {"objects.csv", scene_objects_csv(r)}};
  for (const auto& [name, text] : files) {
    const std::filesystem::path path = std::filesystem::path(dir) / name;
    std::ofstream file(path);
    file << text;
    if (!file.flush()) return invalid_argument("cannot write " + path.string());
  }
  return {};
}

}  // namespace glimpse

// The protocol's pure building blocks: objects, exploration stages and their prefix cuts, folds.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <numeric>
#include <random>

#include "glimpse/dataset.h"
#include "glimpse/evaluation.h"
#include "glimpse/views.h"
#include "glimpse/zoo.h"
#include "parallel.h"

namespace glimpse {

// ---- Objects ---------------------------------------------------------------------------------------

Expected<std::vector<EvalObject>> load_dataset_objects(const std::string& dir, uint64_t seed,
                                                       size_t max_per_category, int threads, const Sizing& sizing) {
  auto dataset = scan_dataset(dir);
  if (!dataset.ok()) return dataset.error();
  std::vector<const DatasetObject*> chosen;
  std::map<std::string, size_t> taken;
  for (const DatasetObject& o : dataset->objects)
    if (max_per_category == 0 || taken[o.category]++ < max_per_category) chosen.push_back(&o);
  std::string source = std::filesystem::path(dir).lexically_normal().filename().string();
  if (source.empty()) source = std::filesystem::path(dir).lexically_normal().parent_path().filename().string();

  std::vector<EvalObject> out(chosen.size());
  std::vector<Error> errors(chosen.size());
  std::vector<char> failed(chosen.size(), 0);
#pragma omp parallel for schedule(dynamic, 1) num_threads(resolve_threads(threads))
  for (int64_t i = 0; i < static_cast<int64_t>(chosen.size()); ++i) {
    auto mesh = load_object(*chosen[i], seed, sizing);
    if (!mesh.ok()) {
      failed[i] = 1;
      errors[i] = mesh.error();
      continue;
    }
    out[i].category = chosen[i]->category;
    out[i].id = chosen[i]->id;
    out[i].mesh = std::move(*mesh);
    out[i].source = source;
    out[i].any_pose = chosen[i]->size.any_pose;
  }
  for (size_t i = 0; i < chosen.size(); ++i)
    if (failed[i]) return errors[i];
  return out;
}

std::vector<EvalObject> zoo_objects(size_t per_category, uint64_t seed) {
  std::vector<EvalObject> out;
  std::map<std::string, int> index;  // id = the object's index within its category
  for (LabelledMesh& m : make_zoo(per_category, seed)) {
    EvalObject o;
    o.id = std::to_string(index[m.category]++);
    o.any_pose = category_size(m.category).any_pose;
    o.category = std::move(m.category);
    o.mesh = std::move(m.mesh);
    o.source = "zoo";
    out.push_back(std::move(o));
  }
  return out;
}

std::vector<EvalObject> common_height(std::vector<EvalObject> objects, float height_m) {
  for (EvalObject& o : objects) o.mesh = place_on_ground(scale_to_height(std::move(o.mesh), height_m));
  return objects;
}

std::vector<std::string> paper_category_order(const std::vector<EvalObject>& objects) {
  static const char* const kPaper[] = {"human", "chair", "table", "mechanic", "fourleg"};
  std::vector<std::string> present;
  for (const EvalObject& o : objects)
    if (std::find(present.begin(), present.end(), o.category) == present.end()) present.push_back(o.category);
  std::vector<std::string> out;
  for (const char* name : kPaper)
    if (std::find(present.begin(), present.end(), name) != present.end()) out.push_back(name);
  std::vector<std::string> rest;
  for (const std::string& c : present)
    if (std::find(out.begin(), out.end(), c) == out.end()) rest.push_back(c);
  std::sort(rest.begin(), rest.end());
  out.insert(out.end(), rest.begin(), rest.end());
  return out;
}

// ---- Stages ----------------------------------------------------------------------------------------

std::string stage_name(const Stage& stage) {
  char buf[32];
  switch (stage.kind) {
    case StageKind::kFull: return "full";
    case StageKind::kKeypoints: std::snprintf(buf, sizeof buf, "%gkp", stage.value); return buf;
    case StageKind::kFraction: std::snprintf(buf, sizeof buf, "%g%%", 100.0 * stage.value); return buf;
  }
  return "?";
}

std::vector<Stage> paper_stages() {
  return {{StageKind::kFull, 0},       {StageKind::kKeypoints, 10}, {StageKind::kKeypoints, 25},
          {StageKind::kKeypoints, 55}, {StageKind::kFraction, 0.10}, {StageKind::kFraction, 0.20}};
}

size_t keypoint_prefix(const Points& view, std::vector<float> keypoint_heights, size_t k, float margin_m) {
  if (k == 0) return 0;
  if (keypoint_heights.size() < k) return view.size();
  std::nth_element(keypoint_heights.begin(), keypoint_heights.begin() + (k - 1), keypoint_heights.end(),
                   std::greater<float>());
  const float cut = keypoint_heights[k - 1] - std::max(0.f, margin_m);
  return static_cast<size_t>(
      std::count_if(view.begin(), view.end(), [cut](const Vec3& p) { return p.z() >= cut; }));
}

size_t fraction_prefix(size_t view_points, size_t full_cloud_points, double fraction) {
  const double n = std::round(std::max(0.0, fraction) * double(full_cloud_points));
  return std::min(view_points, static_cast<size_t>(n));
}

std::vector<size_t> exploration_grid(size_t max_keypoints, size_t step) {
  std::vector<size_t> grid;
  if (max_keypoints == 0) return grid;
  step = std::max<size_t>(1, step);
  grid.push_back(1);
  for (size_t k = step; k <= max_keypoints; k += step)
    if (k > grid.back()) grid.push_back(k);
  if (grid.back() != max_keypoints) grid.push_back(max_keypoints);
  return grid;
}

}  // namespace glimpse

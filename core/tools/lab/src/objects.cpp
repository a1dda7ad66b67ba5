// The protocol's pure building blocks: objects, exploration stages and their prefix cuts, folds.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <numeric>
#include <random>

#include "glimpse/views/dataset.h"
#include "glimpse/lab/evaluation.h"
#include "glimpse/views/placement.h"
#include "glimpse/views/zoo.h"
#include "glimpse/threads.h"

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
  for (LabelledMesh& m : make_zoo(per_category, seed)) {
    EvalObject o;
    o.id = std::move(m.id);
    o.any_pose = m.any_pose;
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

}  // namespace glimpse

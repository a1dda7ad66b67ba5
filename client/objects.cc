#include "client/objects.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include <omp.h>
#include <set>

#include "glimpse/geometry/floor_plane.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/placement.h"
#include "glimpse/views/hidden_point_removal.h"

namespace glimpse::client {
namespace {

std::string Metres(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

std::string SizeText(const CategorySize& s) {
  return s.category + " " + (s.measure == CategorySize::kHeight ? "height " : "largest extent ") + Metres(s.min_m) +
         "-" + Metres(s.max_m) + " m" + (s.any_pose ? " (any pose)" : "");
}

std::string SizingText(const Sizing& sizing) {
  if (sizing.kind == Sizing::kHeight) return "every mesh scaled to " + Metres(sizing.value) + " m tall";
  if (sizing.value == 1.f) return "mesh units are metres";
  return "mesh units x " + Metres(sizing.value) + " m";
}

// What ScanFolder applied, for a person.
std::vector<std::string> Applied(const Folder& f, const Placement& p, bool manifest) {
  std::vector<std::string> out;
  const Dataset& d = f.dataset;
  if (!d.objects.empty())
    out.push_back(std::to_string(d.objects.size()) + " meshes in " + std::to_string(d.categories.size()) +
                  " categories");
  if (!f.clouds.empty()) {
    const Placement& c = f.cloud_placement;
    out.push_back(std::to_string(f.clouds.size()) + " cloud files: " +
                  (c.up ? "up " + up_to_string(*c.up) + " turned to +z (--up)" : std::string("+z up")) + ", " +
                  (c.sizing ? "units x " + Metres(c.sizing->value) + " m (--unit)" : std::string("in metres")) +
                  (c.up || c.sizing ? "" : ", sent as they are"));
  }
  if (d.objects.empty()) return out;
  if (p.up) out.push_back("up: " + up_to_string(*p.up) + " for every mesh (--up)");
  else if (d.has_up_axes)
    out.push_back("up: from up_axis.csv (meshes it does not list: +y)" +
                  (d.unmatched_up_rows ? ", " + std::to_string(d.unmatched_up_rows) + " rows match no mesh" : std::string()));
  else out.push_back("up: +z (no up_axis.csv; --up AXIS to change)");
  if (p.sizing) {
    out.push_back("size: " + SizingText(*p.sizing) + (p.sizing->kind == Sizing::kHeight ? " (--height)" : " (--unit)"));
  } else if (manifest) {
    std::string ranges;
    std::set<std::string> seen;
    for (const DatasetObject& o : d.objects)
      if (seen.insert(o.category).second) ranges += (ranges.empty() ? "" : ", ") + SizeText(o.size);
    out.push_back(std::string("size: real-life ranges per category from ") +
                  (d.has_sizes ? "sizes.csv" : "the defaults") + ", each object drawn in its range: " + ranges);
  } else {
    out.push_back("size: mesh units are metres (no manifest; --unit or --height to change)");
  }
  return out;
}

}  // namespace

Expected<Sizing> ParseUnit(std::string_view text) {
  if (text == "m") return Sizing{Sizing::kUnit, 1.f};
  if (text == "cm") return Sizing{Sizing::kUnit, 0.01f};
  if (text == "mm") return Sizing{Sizing::kUnit, 0.001f};
  if (text == "in") return Sizing{Sizing::kUnit, 0.0254f};
  return invalid_argument("unknown unit '" + std::string(text) + "' (valid: m, cm, mm, in)");
}

std::string ObjectKey(const DatasetObject& object) { return object.category + "/" + object.id; }

Expected<Folder> ScanFolder(const std::string& dir, const Placement& placement) {
  auto listed = ListTrainDir(dir);  // every usable file: meshes and clouds
  if (!listed) return listed.error();
  Folder f;
  auto dataset = scan_dataset(dir);
  if (dataset) {
    f.dataset = std::move(*dataset);
  } else if (dataset.error().code != ErrorCode::kNotFound) {
    return dataset.error();  // a bad manifest row
  }
  std::set<std::string> meshes;
  for (const DatasetObject& o : f.dataset.objects) meshes.insert(o.path);
  for (TrainFile& t : *listed)
    if (!meshes.count(t.path)) f.clouds.push_back(std::move(t));

  if (!f.clouds.empty() && placement.sizing && placement.sizing->kind == Sizing::kHeight)
    return invalid_argument(dir + ": --height scales meshes, and the folder holds " + std::to_string(f.clouds.size()) +
                            " cloud files (e.g. " + f.clouds.front().path +
                            "), which show part of their object, not its height: use --unit for them");
  f.cloud_placement = placement;
  const bool manifest = f.dataset.has_up_axes || f.dataset.has_sizes;
  for (DatasetObject& o : f.dataset.objects) {
    if (placement.up) o.up = *placement.up;
    else if (!f.dataset.has_up_axes) o.up = Vec3::UnitZ();  // the contract's frame: sizes.csv says nothing of up
  }
  if (placement.sizing) f.sizing = *placement.sizing;
  else if (!manifest) f.sizing = Sizing{Sizing::kUnit, 1.f};
  else f.sizing = Sizing{};  // category ranges, as glimpse-lab
  f.applied = Applied(f, placement, manifest);
  return f;
}

Expected<ObjectViews> ProtocolViews(const DatasetObject& object, const Sizing& sizing, const ViewRecipe& recipe,
                                    double sensor_density) {
  auto mesh = load_object(object, recipe.seed, sizing);
  if (!mesh) return mesh.error();
  return training_views(*mesh, ObjectKey(object), object.size.any_pose, recipe, sensor_density);
}

bool ViewsInOrder(size_t count, const MakeViews& make, const TakeViews& take) {
  const int threads = std::max(1, omp_get_max_threads());
  const size_t batch = 2 * static_cast<size_t>(threads);
  std::vector<std::optional<Expected<ObjectViews>>> made;
  for (size_t begin = 0; begin < count; begin += batch) {
    const size_t end = std::min(count, begin + batch);
    made.assign(end - begin, std::nullopt);
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
    for (int64_t i = static_cast<int64_t>(begin); i < static_cast<int64_t>(end); ++i)
      made[static_cast<size_t>(i) - begin].emplace(make(static_cast<size_t>(i)));
    for (size_t i = begin; i < end; ++i)
      if (!take(i, std::move(*made[i - begin]))) return false;
  }
  return true;
}

Status PlaceCloud(Cloud& cloud, const Placement& placement, const std::string& path) {
  if (placement.sizing && placement.sizing->kind == Sizing::kHeight)
    return invalid_argument(path + ": --height scales meshes; a cloud shows part of its object, not its height "
                                   "(--unit gives a cloud's unit)");
  if (!placement.up && !placement.up_floor && !placement.sizing) return {};
  std::error_code ec;
  if (placement.up_floor && std::filesystem::is_directory(path, ec))
    return invalid_argument(path + ": --up floor levels one cloud file by the floor it shows; a folder's frames "
                                   "share one frame: give its up with --up AXIS");
  const float scale = placement.sizing ? placement.sizing->value : 1.f;
  for (Vec3& p : cloud.points) p *= scale;  // first: the floor's fit measures in metres
  if (cloud.sensor) *cloud.sensor *= scale;
  std::optional<Vec3> up = placement.up;
  if (placement.up_floor) {
    Expected<Vec3> floor = floor_up(cloud);
    if (!floor) return invalid_argument(path + ": --up floor: " + floor.error().message);
    up = *floor;
  }
  if (!up) return {};
  const Eigen::Matrix3f r = upright_rotation(*up);
  for (Vec3& p : cloud.points) p = r * p;
  if (cloud.sensor) *cloud.sensor = r * *cloud.sensor;
  if (cloud.frame) cloud.frame->axis = r * cloud.frame->axis, cloud.frame->up = r * cloud.frame->up;
  return {};
}

Expected<Cloud> MeshFileView(const std::string& path, const Placement& placement, const ViewRecipe& recipe,
                             std::optional<int> view) {
  if (placement.up_floor)
    return invalid_argument(path + ": --up floor levels a cloud file by the floor it shows; a mesh shows none: "
                                   "give its up with --up AXIS");
  DatasetObject object;
  object.path = path;
  object.id = std::filesystem::path(path).stem().string();
  object.up = placement.up.value_or(Vec3::UnitZ());
  auto mesh = load_object(object, recipe.seed, placement.sizing.value_or(Sizing{Sizing::kUnit, 1.f}));
  if (!mesh) return mesh.error();
  Points full = full_cloud(*mesh, object.id, recipe);
  if (full.empty()) return invalid_argument(path + ": the mesh gives no points");
  if (!view) return Cloud{std::move(full), std::nullopt, {}};
  const uint64_t seed = object_seed(recipe.seed, object.id);
  return object_view(full, static_cast<size_t>(std::clamp(*view, 0, 5)), 6, false, seed, recipe.hpr_radius_factor);
}

}  // namespace glimpse::client

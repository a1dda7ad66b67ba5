// Mesh folders and single mesh files as the service wants them: read with core's dataset loader
// (dataset.h: the folder's manifest, up axes and real-life sizes, exactly as glimpse-lab reads them),
// or placed by the user's --up / --unit / --height, and cut into the protocol's single views
// (views.h: object_cloud + object_view, seeded by the object's name), so that `glimpse train` and
// `glimpse evaluate` see the lab's views of every object.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "client/inputs.h"
#include "glimpse/dataset.h"
#include "glimpse/evaluation.h"
#include "glimpse/expected.h"

namespace glimpse::client {

// What the user says about meshes that have no manifest (or to override it).
struct Placement {
  std::optional<Vec3> up;         // --up AXIS: this direction of the mesh's own coordinates points up
  std::optional<Sizing> sizing;   // --unit U (kUnit) or --height M (kHeight)
};

// "m", "cm", "mm", "in" -> Sizing::kUnit with the metres per mesh unit.
Expected<Sizing> ParseUnit(std::string_view text);

// How objects are made into views; the defaults are glimpse-lab's.
struct ProtocolOptions {
  size_t points = 6000;      // surface samples per object (0: the mesh's vertices)
  size_t views = 6;          // evenly spaced among the paper's 6 viewpoints; 0: the whole sampled cloud
  double hpr_radius_factor = 100.0;
  uint64_t seed = 42;        // sizes, samples and poses, as glimpse-lab's --seed
  // Training only: more views of the same azimuths from these elevations (deg above the horizon), as
  // glimpse-lab's --train-elevations, so the model learns cameras mounted low or high.
  std::vector<float> train_elevations_deg;
  // Training only: more views of the same azimuths taken by these simulated sensors, filtered down to
  // sensor_density, as glimpse-lab's --train-sensors (evaluation.h: sensor_training_view).
  std::vector<ScanCondition> train_sensors;
  // The relative density (scan_filters.h) the sensors' views are thinned to: the density the model will
  // classify at, the median over every training object's ideal views, which glimpse train measures in a
  // first pass over the objects, as glimpse-lab does (EvalResult::trained_density). 0: not thinned.
  double sensor_density = 0;
};

// A folder DIR/<category>/<files>: its meshes (.off .obj .ply .stl; a .ply without faces gives its
// vertices as the object's cloud, as in glimpse-lab) through core's loader, and the cloud files
// (.pcd .xyz .txt .csv), sent as they are or as the user's --unit / --up place them.
struct Folder {
  Dataset dataset;                 // meshes; each object's up and size as they will be applied
  Sizing sizing;                   // how every mesh is sized
  std::vector<TrainFile> clouds;   // cloud files, not in `dataset`
  Placement cloud_placement;       // the user's --up / --unit, applied to the cloud files (PlaceCloud)
  std::vector<std::string> applied;  // what was applied, one line each, for a person
};

// Reads the folder's listing and manifest (no mesh is read). With a manifest (up_axis.csv or
// sizes.csv) its ups and category sizes apply as in glimpse-lab; without one the meshes are taken as
// the contract has them: +z up, in metres. --up and --unit/--height override either. Errors: the
// folder is missing, holds nothing usable, or a manifest row is bad (naming file and line).
Expected<Folder> ScanFolder(const std::string& dir, const Placement& placement);

// The protocol's views of one object: the mesh loaded (upright, sized, on the ground), its full cloud
// and views exactly as glimpse-lab makes them. Errors name the mesh's path.
struct ObjectViews {
  std::vector<Cloud> views;
  size_t first_augmented = SIZE_MAX;  // views from here on are simulated sensors' (LabelledCloud.augmented)
  size_t full_points = 0;  // the object's full 3D cloud: stages are fractions of it
};
Expected<ObjectViews> ProtocolViews(const DatasetObject& object, const Sizing& sizing, const ProtocolOptions& options);
// The same from a mesh already upright, sized and on the ground (the zoo's), named by `key`.
ObjectViews ViewsOfMesh(const Mesh& mesh, const std::string& key, bool any_pose, const ProtocolOptions& options);

// A cloud file placed as the user says: --unit scales its points (and sensor) to metres, --up turns
// that axis to +z. --height is refused: a cloud shows part of its object, not the object's height.
// Errors name `path`.
Status PlaceCloud(Cloud& cloud, const Placement& placement, const std::string& path);

// A single mesh file (classify, stream): placed by `placement` (default +z up, metres) and seen from
// paper viewpoint `view` (0-5), or whole (the full sampled cloud) when view is nullopt.
Expected<Cloud> MeshFileView(const std::string& path, const Placement& placement, const ProtocolOptions& options,
                             std::optional<int> view);

// "category/id": an object's name in messages and the key of its seed.
std::string ObjectKey(const DatasetObject& object);

}  // namespace glimpse::client

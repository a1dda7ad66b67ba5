// Mesh folders and single mesh files as the service wants them: read with core's dataset loader
// (dataset.h: the folder's manifest, up axes and real-life sizes, exactly as glimpse-lab reads them),
// or placed by the user's --up / --unit / --height, and cut into the protocol's single views
// (learning/object_views.h, seeded by the object's name), so that `glimpse train` and `glimpse evaluate`
// see the lab's views of every object.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "client/inputs.h"
#include "glimpse/views/dataset.h"
#include "glimpse/learning/object_views.h"
#include "glimpse/expected.h"

namespace glimpse::client {

// What the user says about meshes that have no manifest (or to override it).
struct Placement {
  std::optional<Vec3> up;         // --up AXIS: this direction of the mesh's own coordinates points up
  bool up_floor = false;          // --up floor: a cloud file's up is the floor it shows (core's floor_up)
  std::optional<Sizing> sizing;   // --unit U (kUnit) or --height M (kHeight)
};

// "m", "cm", "mm", "in" -> Sizing::kUnit with the metres per mesh unit.
Expected<Sizing> ParseUnit(std::string_view text);

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

// The protocol's views of one object (core's training_views, as glimpse-lab makes them): the mesh loaded
// (upright, sized, on the ground), its full cloud and views, the sensors' views thinned to
// `sensor_density` (0: not thinned). Errors name the mesh's path.
Expected<ObjectViews> ProtocolViews(const DatasetObject& object, const Sizing& sizing, const ViewRecipe& recipe,
                                    double sensor_density = 0);

// Calls take(i, views of object i) for i = 0 .. count - 1 in order, the views made by make(i) a few
// objects at a time on every core: what is taken, and in which order, does not depend on the thread
// count. Stops, returning false, when take does.
using MakeViews = std::function<Expected<ObjectViews>(size_t)>;
using TakeViews = std::function<bool(size_t, Expected<ObjectViews>&&)>;
bool ViewsInOrder(size_t count, const MakeViews& make, const TakeViews& take);

// A cloud file placed as the user says: --unit scales its points (and sensor) to metres, --up turns
// that axis to +z; --up floor turns the normal of the largest floor or table the cloud's camera looks
// down on (core's floor_up, on the points in metres) to +z. --height is refused: a cloud shows part of
// its object, not the object's height. Errors name `path`: no floor found, or --up floor for a folder
// (`path` a folder of frames, which share one frame that no single frame's floor may set).
Status PlaceCloud(Cloud& cloud, const Placement& placement, const std::string& path);

// A single mesh file (classify, stream): placed by `placement` (default +z up, metres; --up floor is an
// error naming `path`) and seen from paper viewpoint `view` (0-5), or whole (the full sampled cloud)
// when view is nullopt.
Expected<Cloud> MeshFileView(const std::string& path, const Placement& placement, const ViewRecipe& recipe,
                             std::optional<int> view);

// "category/id": an object's name in messages and the key of its seed.
std::string ObjectKey(const DatasetObject& object);

}  // namespace glimpse::client

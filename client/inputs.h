// Turning what a user has into the clouds the service wants: point-cloud files as they are, meshes
// sampled into clouds (core's sample_surface) and cut into single 2.5D views (hidden point removal
// from the paper's viewpoints), training folders of category sub-folders, and the procedural zoo.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse::client {

struct ViewOptions {
  size_t mesh_points = 8000;  // points sampled on a mesh's surface before views are taken
  int views = 6;              // single views per mesh (0: the whole sampled cloud); at most 6
  double hpr_radius_factor = 100.0;
  uint64_t seed = 1;          // surface sampling seed
};

// Drops points with a NaN or infinite coordinate (PCD files keep NaN points, and the server refuses
// them); returns how many.
size_t RemoveNonFinite(Cloud& cloud);

// The extensions read: .pcd .ply .xyz .txt .csv (clouds) and .off .obj .ply (meshes).
bool IsInputFile(const std::string& path);

// A file as a cloud or a mesh: .pcd/.xyz/.txt/.csv are clouds; .off/.obj/.ply with faces are meshes,
// without faces their vertices are a cloud (a .ply cloud keeps its sensor). Errors name the path.
struct LoadedFile {
  bool is_mesh = false;
  Mesh mesh;
  Cloud cloud;  // when !is_mesh
};
Expected<LoadedFile> LoadFile(const std::string& path);
// `sensor` (the user's --sensor) replaces a cloud file's own; a mesh's views carry their own sensor,
// so giving one for a mesh is an error naming the file.
Status ApplySensor(LoadedFile& file, const std::optional<Vec3>& sensor, const std::string& path);
// A depth camera's full fields of view, degrees.
struct FieldOfView {
  float h_deg = 0, v_deg = 0;
};
// `fov` (the user's --camera-fov HxV): the cloud file is a depth camera's view as PCL writes one
// (io's read_camera_view: its sensor and frame from the PCD VIEWPOINT); the answer then says where the
// frame cuts the object. A mesh or another format is an error naming the file.
Status ApplyCameraFov(LoadedFile& file, const std::optional<FieldOfView>& fov, const std::string& path);

// Points on a mesh's surface, about `points` of them (kInvalidArgument for a mesh with no area).
Expected<Cloud> SampleMesh(const Mesh& mesh, size_t points, uint64_t seed);

// `views` single views of a full cloud by hidden point removal, from viewpoints evenly chosen among
// the paper's six (views >= 6 gives all six); views = 0 gives the cloud itself.
std::vector<Cloud> SingleViews(const Cloud& full, int views, double radius_factor);

// One single view from paper viewpoint `viewpoint` (0-5, azimuth 60*viewpoint deg).
Cloud SingleView(const Cloud& full, int viewpoint, double radius_factor);

// The clouds a training file contributes: a cloud file gives itself, a mesh gives its views.
// Non-finite points are dropped.
Expected<std::vector<Cloud>> TrainingClouds(const std::string& path, const ViewOptions& options);

// The cloud to classify from a file: a cloud file as it is, a mesh sampled (whole, no view).
Expected<Cloud> CloudToClassify(const std::string& path, const ViewOptions& options);

// DIR/<category>/<file>: categories and files sorted by name; hidden entries, other extensions and
// loose files in DIR are skipped. Errors: DIR missing, no category folder with a usable file.
struct TrainFile {
  std::string category;
  std::string object_id;  // "category/file-stem": the views of one mesh share it
  std::string path;
};
Expected<std::vector<TrainFile>> ListTrainDir(const std::string& dir);

}  // namespace glimpse::client

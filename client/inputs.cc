#include "client/inputs.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "glimpse/io/files.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/hidden_point_removal.h"

namespace glimpse::client {
namespace {

namespace fs = std::filesystem;

std::string Extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

bool Hidden(const fs::path& p) { return !p.filename().empty() && p.filename().string()[0] == '.'; }

}  // namespace

size_t RemoveNonFinite(Cloud& cloud) {
  const size_t before = cloud.points.size();
  std::erase_if(cloud.points, [](const Vec3& v) { return !v.allFinite(); });
  return before - cloud.points.size();
}

bool IsInputFile(const std::string& path) {
  const std::string ext = Extension(path);
  return ext == ".pcd" || ext == ".ply" || ext == ".xyz" || ext == ".txt" || ext == ".csv" || ext == ".off" ||
         ext == ".obj" || ext == ".stl";
}

Status ApplySensor(LoadedFile& file, const std::optional<Vec3>& sensor, const std::string& path) {
  if (!sensor) return {};
  if (file.is_mesh) return invalid_argument(path + ": --sensor is for cloud files; a mesh's view has its own sensor");
  file.cloud.sensor = *sensor;
  return {};
}

Status ApplyCameraFov(LoadedFile& file, const std::optional<FieldOfView>& fov, const std::string& path) {
  if (!fov) return {};
  if (file.is_mesh) return invalid_argument(path + ": --camera-fov is for a depth camera's .pcd; a mesh's view has its own camera");
  Expected<Cloud> view = read_camera_view(path, fov->h_deg, fov->v_deg);
  if (!view) return view.error();
  file.cloud.sensor = view->sensor;
  file.cloud.frame = view->frame;
  return {};
}

Expected<LoadedFile> LoadFile(const std::string& path) {
  const std::string ext = Extension(path);
  LoadedFile out;
  if (ext == ".off" || ext == ".obj" || ext == ".ply" || ext == ".stl") {
    Expected<Mesh> mesh = read_mesh(path);
    if (!mesh && ext != ".ply") return mesh.error();
    if (mesh && !mesh->faces.empty()) {
      out.is_mesh = true;
      out.mesh = std::move(*mesh);
      return out;
    }
    if (mesh && ext != ".ply") {  // OFF/OBJ without faces: its vertices are the cloud
      out.cloud.points = std::move(mesh->vertices);
      return out;
    }
  }
  Expected<Cloud> cloud = read_cloud(path);
  if (!cloud) return cloud.error();
  out.cloud = std::move(*cloud);
  return out;
}

Expected<Cloud> SampleMesh(const Mesh& mesh, size_t points, uint64_t seed) {
  const double area = surface_area(mesh);
  if (!(area > 0.0)) return invalid_argument("the mesh has no surface area");
  return sample_surface(mesh, static_cast<double>(points) / area, seed);
}

Cloud SingleView(const Cloud& full, int viewpoint, double radius_factor) {
  const std::vector<Vec3> cameras = paper_viewpoints(full.points);
  if (cameras.empty()) return full;
  const Vec3& camera = cameras[static_cast<size_t>(std::clamp(viewpoint, 0, int(cameras.size()) - 1))];
  return hidden_point_removal(full.points, camera, radius_factor);
}

std::vector<Cloud> SingleViews(const Cloud& full, int views, double radius_factor) {
  if (views <= 0) return {full};
  const std::vector<Vec3> cameras = paper_viewpoints(full.points);
  if (cameras.empty()) return {};
  const size_t n = std::min(static_cast<size_t>(views), cameras.size());
  std::vector<Cloud> out;
  out.reserve(n);
  for (size_t i = 0; i < n; ++i)
    out.push_back(hidden_point_removal(full.points, cameras[i * cameras.size() / n], radius_factor));
  return out;
}

Expected<std::vector<Cloud>> TrainingClouds(const std::string& path, const ViewOptions& options) {
  Expected<LoadedFile> file = LoadFile(path);
  if (!file) return file.error();
  if (!file->is_mesh) {
    RemoveNonFinite(file->cloud);
    return std::vector<Cloud>{std::move(file->cloud)};
  }
  Expected<Cloud> full = SampleMesh(file->mesh, options.mesh_points, options.seed);
  if (!full) return Error{full.error().code, path + ": " + full.error().message};
  RemoveNonFinite(*full);
  return SingleViews(*full, options.views, options.hpr_radius_factor);
}

Expected<Cloud> CloudToClassify(const std::string& path, const ViewOptions& options) {
  Expected<LoadedFile> file = LoadFile(path);
  if (!file) return file.error();
  Cloud cloud = std::move(file->cloud);
  if (file->is_mesh) {
    Expected<Cloud> sampled = SampleMesh(file->mesh, options.mesh_points, options.seed);
    if (!sampled) return Error{sampled.error().code, path + ": " + sampled.error().message};
    cloud = std::move(*sampled);
  }
  RemoveNonFinite(cloud);
  return cloud;
}

Expected<std::vector<TrainFile>> ListTrainDir(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return not_found(dir + ": no such folder");
  std::vector<fs::path> categories;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec))
    if (e.is_directory(ec) && !Hidden(e.path())) categories.push_back(e.path());
  if (ec) return not_found(dir + ": " + ec.message());
  std::sort(categories.begin(), categories.end());

  std::vector<TrainFile> files;
  for (const fs::path& category : categories) {
    std::vector<fs::path> paths;
    for (const fs::directory_entry& e : fs::directory_iterator(category, ec))
      if (e.is_regular_file(ec) && !Hidden(e.path()) && IsInputFile(e.path().string())) paths.push_back(e.path());
    if (ec) return not_found(category.string() + ": " + ec.message());
    std::sort(paths.begin(), paths.end());
    const std::string name = category.filename().string();
    for (const fs::path& p : paths) files.push_back({name, name + "/" + p.stem().string(), p.string()});
  }
  if (files.empty())
    return invalid_argument(dir + ": no category folders with .pcd .ply .xyz .off .obj .stl files");
  return files;
}

}  // namespace glimpse::client

// glimpse-lab views MESH --out DIR: the paper's 6 single views of a mesh (sec. 3.4) as .pcd files,
// each with its camera as the PCD viewpoint; with --sensor depth|lidar, the frames a simulated sensor
// takes from the same 6 azimuths (a folder `glimpse stream --frames` streams).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "glimpse/lab/evaluation.h"
#include "glimpse/io/files.h"
#include "glimpse/views/sensors.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/placement.h"
#include "glimpse/views/hidden_point_removal.h"

namespace glimpse::lab {

namespace {

struct ViewsOptions {
  std::string mesh;
  std::string out = "out/views";
  std::string up = "+y";
  std::string points = "vertices";
  float height_m = 0;
  double radius_factor = 100;
  uint64_t seed = 42;
  std::string sensor = "ideal";
  float distance_m = 2, elevation_deg = 30;
  bool floor = false;
};

int run_views(const ViewsOptions& o) {
  auto mesh = read_mesh(o.mesh);
  if (!mesh.ok()) {
    std::fprintf(stderr, "glimpse-lab views: %s\n", mesh.error().message.c_str());
    return 1;
  }
  auto up = parse_up(o.up);
  if (!up.ok()) {
    std::fprintf(stderr, "glimpse-lab views: --up: %s\n", up.error().message.c_str());
    return 2;
  }
  if (mesh->vertices.empty()) {
    std::fprintf(stderr, "glimpse-lab views: %s: no vertices, nothing to view\n", o.mesh.c_str());
    return 1;
  }
  Mesh m = stand_upright(std::move(*mesh), *up);
  if (o.height_m > 0) m = scale_to_height(std::move(m), o.height_m);
  m = place_on_ground(std::move(m));
  Cloud cloud;
  if (o.points == "vertices") {
    cloud = mesh_vertices(m);
  } else {
    char* end = nullptr;
    const long n = std::strtol(o.points.c_str(), &end, 10);
    if (n <= 0 || *end) {
      std::fprintf(stderr, "glimpse-lab views: --points must be 'vertices' or a positive count, not '%s'\n", o.points.c_str());
      return 2;
    }
    const double area = surface_area(m);
    if (!(area > 0)) {
      std::fprintf(stderr, "glimpse-lab views: %s: the mesh has no area to sample (--points vertices takes its vertices)\n",
                   o.mesh.c_str());
      return 1;
    }
    cloud = sample_surface(m, double(n) / area, o.seed);
  }
  auto sensor = parse_sensor(o.sensor);
  if (!sensor.ok()) {
    std::fprintf(stderr, "glimpse-lab views: --sensor: %s\n", sensor.error().message.c_str());
    return 2;
  }
  auto lidar = lidar_with_beams(sensor->beams);
  std::optional<RayScene> scene;
  if (sensor->sensor != SensorKind::kIdeal) {
    const Bounds b = bounds(m.vertices);
    auto built = RayScene::build(m, o.floor ? 0.5f * std::max(b.extent().x(), b.extent().y()) + 0.5f : 0.f);
    if (!built.ok()) {
      std::fprintf(stderr, "glimpse-lab views: %s: %s\n", o.mesh.c_str(), built.error().message.c_str());
      return 1;
    }
    scene = std::move(*built);
  }
  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  const std::vector<Vec3> cameras = paper_viewpoints(cloud.points);
  for (size_t i = 0; i < cameras.size(); ++i) {
    Cloud view;
    if (!scene) {
      view = hidden_point_removal(cloud.points, cameras[i], o.radius_factor);
    } else {
      const SensorPose pose = orbit_pose(scene->object_bounds().centre(), 60.f * float(i), o.elevation_deg, o.distance_m);
      view = sensor->sensor == SensorKind::kDepthCamera ? depth_camera_scan(*scene, pose, DepthCameraParams{}, o.seed + i)
                                                        : lidar_scan(*scene, pose, *lidar, o.seed + i);
    }
    const std::string path = (std::filesystem::path(o.out) / ("view_" + std::to_string(60 * i) + ".pcd")).string();
    if (Status s = write_cloud(path, view); !s.ok()) {
      std::fprintf(stderr, "glimpse-lab views: %s\n", s.error().message.c_str());
      return 1;
    }
    if (scene)
      std::printf("%s: %zu points from azimuth %zu deg, %g m, %g deg up\n", path.c_str(), view.points.size(), 60 * i,
                  double(o.distance_m), double(o.elevation_deg));
    else
      std::printf("%s: %zu of %zu points visible from azimuth %zu deg\n", path.c_str(), view.points.size(),
                  cloud.points.size(), 60 * i);
  }
  return 0;
}

}  // namespace

void add_views_command(CLI::App& app) {
  auto o = std::make_shared<ViewsOptions>();
  CLI::App* cmd = app.add_subcommand("views", "write the 6 HPR single views of a mesh (sec. 3.4) as .pcd files");
  cmd->add_option("mesh", o->mesh, "mesh file (.off, .obj, .ply, .stl)")->required();
  cmd->add_option("--out", o->out, "output folder")->capture_default_str();
  cmd->add_option("--up", o->up, "the mesh axis that points up (+x, -y, +z, ...)")->capture_default_str();
  cmd->add_option("--points", o->points, "'vertices' or N area-weighted surface samples")->capture_default_str();
  cmd->add_option("--height", o->height_m, "scale to this height in metres (0: keep the mesh units)");
  cmd->add_option("--hpr-radius", o->radius_factor, "HPR spherical-flip radius factor")->capture_default_str();
  cmd->add_option("--seed", o->seed, "surface sampling and sensor noise seed")->capture_default_str();
  cmd->add_option("--sensor", o->sensor,
                  "ideal: HPR views of surface samples (the paper); depth / lidar: frames a simulated Kinect-class "
                  "camera or a LiDAR of 16 beams (lidar, lidar16), 32 (lidar32) or 64 (lidar64) takes from the same azimuths "
                  "(ray cast, with its noise)")
      ->capture_default_str();
  cmd->add_option("--distance", o->distance_m, "depth / lidar: metres from the object's centre")->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--elevation", o->elevation_deg, "depth / lidar: degrees above the horizon")->capture_default_str()
      ->check(CLI::Range(-90.f, 90.f));
  cmd->add_flag("--floor", o->floor, "depth / lidar: a floor patch under the object, seen by the sensor");
  cmd->callback([o] {
    if (int rc = run_views(*o); rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace glimpse::lab

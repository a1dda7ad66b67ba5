// glimpse-lab views MESH --out DIR: the paper's 6 single views of a mesh (sec. 3.4) as .pcd files,
// each with its camera as the PCD viewpoint.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "glimpse/io.h"
#include "glimpse/views.h"

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
  Mesh m = stand_upright(std::move(*mesh), *up);
  if (o.height_m > 0) m = scale_to_height(std::move(m), o.height_m);
  m = place_on_ground(std::move(m));
  Cloud cloud;
  if (o.points == "vertices") {
    cloud = mesh_vertices(m);
  } else {
    const long n = std::strtol(o.points.c_str(), nullptr, 10);
    const double area = surface_area(m);
    if (n <= 0 || !(area > 0)) {
      std::fprintf(stderr, "glimpse-lab views: --points must be 'vertices' or a positive count (mesh area %g)\n", area);
      return 2;
    }
    cloud = sample_surface(m, double(n) / area, o.seed);
  }
  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  const std::vector<Vec3> cameras = paper_viewpoints(cloud.points);
  for (size_t i = 0; i < cameras.size(); ++i) {
    const Cloud view = hidden_point_removal(cloud.points, cameras[i], o.radius_factor);
    const std::string path = (std::filesystem::path(o.out) / ("view_" + std::to_string(60 * i) + ".pcd")).string();
    if (Status s = write_cloud(path, view); !s.ok()) {
      std::fprintf(stderr, "glimpse-lab views: %s\n", s.error().message.c_str());
      return 1;
    }
    std::printf("%s: %zu of %zu points visible from azimuth %zu deg\n", path.c_str(), view.points.size(),
                cloud.points.size(), 60 * i);
  }
  return 0;
}

}  // namespace

void add_views_command(CLI::App& app) {
  auto o = std::make_shared<ViewsOptions>();
  CLI::App* cmd = app.add_subcommand("views", "write the 6 HPR single views of a mesh (sec. 3.4) as .pcd files");
  cmd->add_option("mesh", o->mesh, "mesh file (.off, .obj, .ply)")->required();
  cmd->add_option("--out", o->out, "output folder")->capture_default_str();
  cmd->add_option("--up", o->up, "the mesh axis that points up (+x, -y, +z, ...)")->capture_default_str();
  cmd->add_option("--points", o->points, "'vertices' or N area-weighted surface samples")->capture_default_str();
  cmd->add_option("--height", o->height_m, "scale to this height in metres (0: keep the mesh units)");
  cmd->add_option("--hpr-radius", o->radius_factor, "HPR spherical-flip radius factor")->capture_default_str();
  cmd->add_option("--seed", o->seed, "surface sampling seed")->capture_default_str();
  cmd->callback([o] {
    if (int rc = run_views(*o); rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace glimpse::lab

// glimpse scene: one frame of a scanner that sees a room, sent whole over ClassifyScene; every object the
// server finds is printed with its box and category (a table, or one JSON object), and --svg draws the
// frame from above with each object's box labelled.
#include <fstream>

#include "client/commands.h"
#include "client/parse.h"
#include "client/render.h"
#include "client/render_scene.h"
#include "proto/wire/clouds.h"
#include "proto/wire/errors.h"
#include "proto/wire/methods.h"

namespace glimpse::client {
namespace {

constexpr double kTimeoutS = 60;

// The frame as sent: a cloud file's finite points, its sensor (the origin, a camera's own coordinates,
// when the file names none), levelled by --up.
Expected<Cloud> ReadFrame(const SceneOptions& o) {
  auto loaded = LoadFile(o.file);
  if (!loaded) return loaded.error();
  if (loaded->is_mesh)
    return invalid_argument(o.file + ": a mesh; glimpse scene takes a scanner's frame (.pcd .ply .xyz), every object "
                                     "of which it finds and classifies (glimpse classify takes a mesh's view)");
  if (Status s = ApplySensor(*loaded, o.sensor, o.file); !s.ok()) return s.error();
  if (!loaded->cloud.sensor) loaded->cloud.sensor = Vec3::Zero();
  if (Status s = ApplyCameraFov(*loaded, o.camera_fov, o.file); !s.ok()) return s.error();
  RemoveNonFinite(loaded->cloud);
  if (loaded->cloud.points.empty()) return invalid_argument(o.file + ": the frame has no point with a depth");
  if (Status s = PlaceCloud(loaded->cloud, o.placement, o.file); !s.ok()) return s.error();
  return std::move(loaded->cloud);
}

v1::ClassifySceneRequest SceneRequest(const SceneOptions& o, const Cloud& frame) {
  v1::ClassifySceneRequest request;
  *request.mutable_model() = *ParseModelRef(o.model);
  if (!o.method.empty()) request.set_method(*wire::ParseMethod(o.method));
  wire::CloudToProto(frame, request.mutable_frame());
  request.set_known_acceptance(o.known_acceptance);
  request.set_return_indices(!o.svg.empty());
  v1::SceneParameters* p = request.mutable_scene();
  if (o.cluster_tolerance_m) p->set_cluster_tolerance_m(*o.cluster_tolerance_m);
  if (o.min_object_points) p->set_min_object_points(*o.min_object_points);
  if (o.reference_density) p->set_reference_density_per_deg2(*o.reference_density);
  if (o.max_object_extent_m) p->set_max_object_extent_m(*o.max_object_extent_m);
  return request;
}

Status WriteSvg(const SceneOptions& o, const v1::ClassifySceneResponse& response, const Cloud& frame) {
  std::ofstream out(o.svg, std::ios::binary | std::ios::trunc);
  out << SceneSvg(o.file, response, frame.points, frame.sensor);
  out.close();
  if (!out) return invalid_argument(o.svg + ": cannot write the SVG");
  return {};
}

}  // namespace

int RunScene(const ConnectionOptions& conn, const SceneOptions& o) {
  const std::string what = "scene " + o.file;
  auto frame = ReadFrame(o);
  if (!frame) {
    PrintError(what, std::string(wire::StatusCodeName(wire::ToGrpcCode(frame.error().code))) + ": " +
                         frame.error().message);
    return kExitError;
  }
  auto stub = ConnectGlimpse(conn, what);
  if (!stub) return kExitError;
  grpc::ClientContext context;
  PrepareContext(context, conn, kTimeoutS);
  v1::ClassifySceneResponse response;
  if (grpc::Status s = stub->ClassifyScene(&context, SceneRequest(o, *frame), &response); !s.ok()) {
    PrintError(what, FormatStatus(s));
    return kExitError;
  }
  if (!response.warning().empty()) PrintError(what, "warning: " + response.warning());
  if (o.json) {
    PrintOut(SceneJson(o.file, response) + "\n");
  } else {
    PrintOut("model " + FormatModelRef(response.model()) + "  method " + wire::MethodName(response.method()) + "  " +
             std::to_string(response.objects_size()) + " objects, " + std::to_string(response.planes_size()) +
             " planes, " + std::to_string(response.frame_points()) + " points, " + Fixed(response.total_ms(), 0) +
             " ms\n" + (response.objects_size() > 0 ? SceneTable(response) : std::string()));
  }
  if (!o.svg.empty())
    if (Status s = WriteSvg(o, response, *frame); !s.ok()) {
      PrintError(what, s.error().message);
      return kExitError;
    }
  return kExitOk;  // an object that could not be classified is a row of the answer, not a failed call
}

}  // namespace glimpse::client

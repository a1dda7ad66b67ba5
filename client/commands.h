// The glimpse subcommands: each takes the connection options and its own options, talks to the
// server through the generated stubs, prints its result, and returns an exit code (connection.h).
// Errors go to stderr as "glimpse: <command> <subject>: <CODE>: <message>". Nothing throws.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "client/connection.h"
#include "client/inputs.h"
#include "client/objects.h"
#include "client/parse.h"

namespace glimpse::client {

// grpc.health.v1.Health/Check of `service` ("" = the whole server); 0 only when SERVING.
int RunHealth(const ConnectionOptions& conn, const std::string& service);

// Model references are "NAME[:VERSION]" already checked by ParseModelRef.
int RunModelsList(const ConnectionOptions& conn, const std::string& name, bool json);
int RunModelsShow(const ConnectionOptions& conn, const std::string& ref, bool json);
int RunModelsDelete(const ConnectionOptions& conn, const std::string& ref);
int RunModelsSetDefault(const ConnectionOptions& conn, const std::string& ref);

struct TrainOptions {
  std::string dir;             // DIR/<category>/<files>; empty with zoo
  bool zoo = false;            // the core's procedural shape zoo: alone, or added to DIR (its categories)
  size_t per_category = 4;     // zoo objects per category
  std::string name;            // empty with base: the base's name
  std::string base;            // "NAME[:VERSION]": grow that version (its methods and parameters)
  std::string methods;         // "bok,bog"; empty: the server's default set
  std::string description;
  Placement placement;         // --up, --unit, --height (override the folder's manifest)
  ViewRecipe protocol;    // views, samples, seed (glimpse-lab's defaults)
  std::optional<uint64_t> train_seed;  // TrainParameters.seed
  bool no_scan_filters = false;        // TrainParameters.filter_scans = false
  bool json = false;           // print the stored ModelInfo as JSON instead of a summary
  bool quiet = false;          // no progress
};
int RunTrain(const ConnectionOptions& conn, const TrainOptions& options);

struct ClassifyOptions {
  std::vector<std::string> files;
  std::string model;   // "NAME[:VERSION]"
  std::string method;  // empty: the model's default
  Placement placement;       // meshes: --up, --unit, --height
  ViewRecipe protocol;  // meshes: samples, seed
  int view = 0;              // meshes: the paper's viewpoint (0-5) of the single view sent
  bool whole = false;        // meshes: the whole sampled cloud instead of a view
  bool view_given = false;   // --view or --whole was given (a cloud file, sent as it is, is warned)
  std::optional<Vec3> sensor;  // clouds: the sensor position, replacing the file's (a PCD's identity
                               // VIEWPOINT reads as "no sensor"; --sensor 0,0,0 says it is at the origin)
  std::optional<FieldOfView> camera_fov;  // .pcd clouds: a depth camera's view, its pose the VIEWPOINT's
  bool json = false;         // one JSON object per file, errors included
  double known_acceptance = 0;  // the operating point of "unknown" (0: the model's default)
};
int RunClassify(const ConnectionOptions& conn, const ClassifyOptions& options);

struct SceneOptions {
  std::string file;            // one frame: a cloud file
  std::string model;           // "NAME[:VERSION]"
  std::string method;          // empty: the model's default
  Placement placement;         // --up AXIS|floor, --unit
  std::optional<Vec3> sensor;  // as ClassifyOptions::sensor; none in the file: the origin
  std::optional<FieldOfView> camera_fov;  // as ClassifyOptions::camera_fov
  std::string svg;             // write the top view here
  bool json = false;
  double known_acceptance = 0;
  std::optional<float> cluster_tolerance_m, max_object_extent_m;  // SceneParameters; unset: the server's
  std::optional<uint32_t> min_object_points;
  std::optional<float> reference_density;
};
int RunScene(const ConnectionOptions& conn, const SceneOptions& options);

struct StreamOptions {
  std::string file;           // or zoo_category, or frames_dir
  std::string frames_dir;     // a folder of frames, each from its own sensor (frames.h)
  std::optional<v1::TrackTarget> track;  // with frames_dir: follow this object, each frame sent whole
  std::string zoo_category;
  uint64_t seed = 42;         // zoo shape, random order, mesh samples
  std::string model;
  std::string method;
  size_t chunks = 20;         // used when chunk_points == 0
  size_t chunk_points = 0;
  std::string order = "top-down";
  double rate_hz = 5.0;       // chunks per second; 0: as fast as the server answers
  // Which of the paper's six viewpoints takes the single view: meshes and zoo shapes always need one
  // (default 0); a cloud file streams as it is unless a view is asked for.
  std::optional<int> viewpoint;
  std::optional<Vec3> sensor;  // cloud files: as ClassifyOptions::sensor
  std::optional<FieldOfView> camera_fov;  // as ClassifyOptions::camera_fov
  Placement placement;        // meshes: --up, --unit, --height
  ViewRecipe protocol;   // meshes: samples
  bool json = false;
  double known_acceptance = 0;  // the operating point of "unknown" (0: the model's default)
};
int RunStream(const ConnectionOptions& conn, const StreamOptions& options);

// The single view a stream reveals (see StreamOptions::viewpoint); errors name the file.
Expected<Cloud> StreamView(const StreamOptions& options);
// The chunks a stream sends: the view revealed in the given order and cut into chunks (all with its
// sensor), or the frames of frames_dir in order (each chunk with its frame's sensor).
Expected<std::vector<Cloud>> StreamChunks(const StreamOptions& options);

struct EvaluateOptions {
  std::string dir;             // DIR/<category>/<meshes>, labelled by folder
  std::string model;           // "NAME[:VERSION]"
  std::string method;          // empty: the model's default
  std::string stages = "full,10,20";  // full and N (% of the object's full cloud, top-down)
  Placement placement;
  ViewRecipe protocol;
  size_t max_per_category = 0;  // 0: every object
  size_t batch_clouds = 48;    // clouds per ClassifyBatch call
  bool json = false;
  bool quiet = false;
};
int RunEvaluate(const ConnectionOptions& conn, const EvaluateOptions& options);

}  // namespace glimpse::client

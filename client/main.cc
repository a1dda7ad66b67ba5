// glimpse: the command-line client of the glimpse.v1.Glimpse service. This file only parses the
// command line (CLI11) and hands over to commands.h. Exit codes: 0 ok, 1 error, 2 usage.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <functional>

#include "client/commands.h"
#include "client/evaluate.h"
#include "client/parse.h"
#include "client/scan.h"
#include "glimpse/views/placement.h"
#include "glimpse/learning/object_views.h"
#include "glimpse/views/scan_conditions.h"
#include "glimpse/views/zoo.h"
#include "proto/wire/methods.h"

using namespace glimpse::client;

namespace {

// CLI11 check: empty string when valid, else the reason.
template <class Parse>
CLI::Validator Checked(Parse parse, const std::string& description) {
  return CLI::Validator(
      [parse](std::string& text) -> std::string {
        auto parsed = parse(text);
        return parsed ? std::string() : parsed.error().message;
      },
      description);
}

const CLI::Validator kModelRef = Checked([](std::string_view s) { return ParseModelRef(s); }, "NAME[:VERSION]");
const CLI::Validator kMethod = Checked(glimpse::wire::ParseMethod, "METHOD");
const CLI::Validator kMethodList = Checked(ParseMethodList, "M1,M2,..");
const CLI::Validator kOrder = Checked(ParseRevealOrder, "top-down|random|sweep");
const CLI::Validator kSensor = Checked(ParseSensor, "X,Y,Z");
const CLI::Validator kFieldOfView = Checked(ParseFieldOfView, "HxV");
// The share of known clouds to accept: (0, 1] (the wire's 0 is "the model's default", never asked).
const CLI::Validator kAcceptance(
    [](std::string& text) -> std::string {
      char* end = nullptr;
      const double v = std::strtod(text.c_str(), &end);
      return !text.empty() && *end == '\0' && v > 0 && v <= 1 ? std::string() : "must be in (0, 1], not " + text;
    },
    "(0, 1]");
// The training sensors of the recipe (core's default_training_sensors).
const std::string kSensorViews = glimpse::training_sensors_spec(glimpse::default_training_sensors());

void AddConnectionOptions(CLI::App& app, ConnectionOptions& conn) {
  app.add_option("--server", conn.server, "server address host:port")->envname("GLIMPSE_SERVER")
      ->capture_default_str()->group("Connection");
  app.add_option_function<double>("--timeout", [&conn](const double& s) { conn.timeout_s = s; },
                                  "deadline of every call in seconds [health 5, models 30, classify 60 per file, "
                                  "stream 120 + scan time, train 3600]")
      ->check(CLI::PositiveNumber)->group("Connection");
  auto* tls = app.add_flag("--tls", conn.tls, "connect with TLS")->group("Connection");
  auto* ca = app.add_option("--ca", conn.ca_file, "PEM CA certificate(s) to trust (default: system roots)")
                 ->check(CLI::ExistingFile)->group("Connection");
  auto* cert = app.add_option("--cert", conn.cert_file, "PEM client certificate for mutual TLS (with --key)")
                   ->check(CLI::ExistingFile)->group("Connection");
  auto* key = app.add_option("--key", conn.key_file, "PEM private key of --cert")
                  ->check(CLI::ExistingFile)->group("Connection");
  ca->needs(tls);
  cert->needs(tls)->needs(key);
  key->needs(tls)->needs(cert);
  app.add_option("--token", conn.token, "bearer token sent as 'authorization: Bearer <token>'")
      ->envname("GLIMPSE_TOKEN")->group("Connection");
}

// Where a cloud file's sensor was.
CLI::Option* AddSensorOption(CLI::App& cmd, std::optional<glimpse::Vec3>& sensor) {
  return cmd.add_option_function<std::string>("--sensor", [&sensor](const std::string& t) { sensor = *ParseSensor(t); },
                                              "cloud files: where the sensor was, X,Y,Z in the cloud's frame (replaces "
                                              "the file's; a PCD's default VIEWPOINT 0 0 0 1 0 0 0 reads as no sensor)")
      ->check(kSensor);
}

// A cloud file that is one depth camera's view: its fields of view (the pose is the PCD VIEWPOINT's).
CLI::Option* AddCameraFovOption(CLI::App& cmd, std::optional<FieldOfView>& fov) {
  return cmd.add_option_function<std::string>("--camera-fov", [&fov](const std::string& t) { fov = *ParseFieldOfView(t); },
                                              "a .pcd that is one depth camera's view: its full fields of view HxV in "
                                              "degrees (57x43 for a Kinect), the camera at the VIEWPOINT looking along "
                                              "its +z, image up its -y (PCL's convention); the answer names the edges "
                                              "of the image the object reaches (cut by the frame)")
      ->check(kFieldOfView);
}

// How the files are stood up and sized: meshes (`folder`: a folder's, whose manifest these override)
// and, where `clouds`, cloud files alike, except --height, which sizes meshes only; --up floor where a
// single cloud file is read (classify, stream).
void AddPlacementOptions(CLI::App& cmd, Placement& placement, bool folder, bool clouds) {
  const std::string which = clouds ? "meshes and clouds" : "meshes";
  const bool floor = clouds && !folder;  // a single cloud file: classify, stream
  cmd.add_option_function<std::string>("--up",
                                       [&placement, floor](const std::string& t) {
                                         const UpChoice up = *ParseUpChoice(t, floor);
                                         placement.up = up.axis, placement.up_floor = up.floor;
                                       },
                                       "the files' axis that points up, turned to +z: +z, -y, x, ... or \"x y z\"; " +
                                           which + (folder ? " (overrides up_axis.csv)" : "") +
                                           (floor ? "; 'floor': a cloud file's up is the normal of the largest floor "
                                                    "or table its camera looks down on (a depth camera's frame in "
                                                    "its own coordinates)"
                                                  : ""))
      ->check(Checked([floor](std::string_view t) { return ParseUpChoice(t, floor); }, floor ? "AXIS|floor" : "AXIS"))
      ->group("Placement");
  auto* unit = cmd.add_option_function<std::string>(
                      "--unit", [&placement](const std::string& t) { placement.sizing = *ParseUnit(t); },
                      "the files' unit: m, cm, mm, in; " + which + (folder ? " (overrides sizes.csv)" : ""))
                   ->check(Checked(ParseUnit, "m|cm|mm|in"))->group("Placement");
  cmd.add_option_function<float>("--height",
                                 [&placement](const float& m) { placement.sizing = glimpse::Sizing{glimpse::Sizing::kHeight, m}; },
                                 std::string("scale every mesh to this height in metres") +
                                     (folder ? " (overrides sizes.csv)" : "") + (clouds ? "; not for cloud files" : ""))
      ->check(CLI::PositiveNumber)->excludes(unit)->group("Placement");
}

// Surface samples and their seed; train and evaluate also choose the number of views.
void AddViewOptions(CLI::App& cmd, glimpse::ViewRecipe& p, bool views) {
  cmd.add_option("--mesh-points", p.points, "points sampled on a mesh's surface (0: its vertices), as glimpse-lab's --points")
      ->capture_default_str()->check(CLI::Range(size_t{0}, size_t{5'000'000}))->group("Meshes");
  cmd.add_option("--seed", p.seed, std::string("seed of sizes, samples and poses (glimpse-lab's --seed)") +
                                       (cmd.get_name() == "train" ? ", and of zoo shapes" : ""))
      ->capture_default_str()->group("Meshes");
  if (views)
    cmd.add_option("--views", p.views, "single views (hidden point removal) per mesh or zoo shape, 0 = the whole cloud")
        ->capture_default_str()->check(CLI::Range(size_t{0}, size_t{6}))->group("Meshes");
}

// Every command's options: CLI11 binds references to these fields and fills them while it parses; the
// parsed command's callback sets `run`.
struct CommandLine {
  ConnectionOptions conn;
  std::string health_service;
  std::string list_name, show_ref, delete_ref, default_ref;
  bool list_json = false, show_json = false;
  TrainOptions train;
  ClassifyOptions classify;
  SceneOptions scene;
  StreamOptions stream;
  EvaluateOptions evaluate;
  std::function<int()> run;
};

void AddHealth(CLI::App& app, CommandLine& cl) {
  auto* health = app.add_subcommand("health", "check the server's health (exit 0 when SERVING)");
  health->add_option("--service", cl.health_service, "service to check (default: the whole server)");
  health->callback([&cl] { cl.run = [&cl] { return RunHealth(cl.conn, cl.health_service); }; });
}

void AddModels(CLI::App& app, CommandLine& cl) {
  auto* models = app.add_subcommand("models", "list, show, delete models, and choose the default version");
  models->require_subcommand(1);
  auto* list = models->add_subcommand("list", "list every model version (or one name's)");
  list->add_option("NAME", cl.list_name, "only this name's versions");
  list->add_flag("--json", cl.list_json, "one JSON object per line");
  list->callback([&cl] { cl.run = [&cl] { return RunModelsList(cl.conn, cl.list_name, cl.list_json); }; });
  auto* show = models->add_subcommand("show", "details of one model (NAME: its default version)");
  show->add_option("MODEL", cl.show_ref, "NAME[:VERSION]")->required()->check(kModelRef);
  show->add_flag("--json", cl.show_json, "as JSON");
  show->callback([&cl] { cl.run = [&cl] { return RunModelsShow(cl.conn, cl.show_ref, cl.show_json); }; });
  auto* del = models->add_subcommand("delete", "delete a version (NAME:VERSION) or every version (NAME)");
  del->add_option("MODEL", cl.delete_ref, "NAME[:VERSION]")->required()->check(kModelRef);
  del->callback([&cl] { cl.run = [&cl] { return RunModelsDelete(cl.conn, cl.delete_ref); }; });
  auto* set_default = models->add_subcommand("set-default", "serve NAME:VERSION when NAME is asked for "
                                                            "(NAME:latest: serve the newest)");
  set_default->add_option("MODEL", cl.default_ref, "NAME:VERSION or NAME:latest")->required()
      ->check(Checked([](std::string_view s) { return ParseModelRef(s, /*allow_latest=*/true); }, "NAME:VERSION"));
  set_default->callback([&cl] { cl.run = [&cl] { return RunModelsSetDefault(cl.conn, cl.default_ref); }; });
}

// Where the training views come from besides the paper's: more elevations and simulated sensors.
void AddTrainingViewOptions(CLI::App& train, TrainOptions& t) {
  train.add_option("--elevations", t.protocol.train_elevations_deg,
                   "more training views of each mesh from these elevations (degrees above the horizon, besides the "
                   "paper's 30), as glimpse-lab's --train-elevations: for cameras mounted low or high (0,15 "
                   "measured in the README; training takes several times longer)")
      ->delimiter(',')->check(CLI::Range(-90.f, 90.f))->group("Meshes");
  train.add_option_function<std::string>(
           "--sensor-views",
           [&t](const std::string& text) { t.protocol.train_sensors = *glimpse::parse_training_sensors(text); },
           "more training views of each mesh taken by simulated sensors, SENSOR:METRES:DEGREES[,...] (depth, "
           "lidar, lidar32 or lidar64, from that distance and elevation, or ranges such as depth:0.8-4:-10-60 from "
           "which each view draws its pose; an item listed again draws again; filtered to the median density of every mesh's ideal views, "
           "measured in a first pass; sent marked augmented: "
           "learnt, but never what 'unknown' measures a cloud against), as glimpse-lab's --train-sensors; 'none': the paper's views alone (default: " + kSensorViews + ", the recipe the README "
           "measures; training takes about 4 times longer)")
      ->check(Checked([](const std::string& s) { return glimpse::parse_training_sensors(s); }, "LIST"))
      ->group("Meshes");
}

CLI::App* AddTrain(CLI::App& app, CommandLine& cl) {
  auto* train = app.add_subcommand("train", "train a new model version from DIR/<category>/<files> or the shape zoo.\n"
                                            "Meshes are read as glimpse-lab reads them: up axes and real-life sizes from\n"
                                            "DIR/up_axis.csv and DIR/sizes.csv; without them +z up and metres (--up, --unit,\n"
                                            "--height); each cut into the protocol's single views. Cloud files go as they are.");
  TrainOptions& t = cl.train;
  t.protocol.train_sensors = glimpse::default_training_sensors();
  train->add_option("DIR", t.dir, "folder of category folders of .off .obj .ply .stl meshes or .pcd .xyz clouds")
                  ->check(CLI::ExistingDirectory);
  train->add_flag("--zoo", t.zoo, "train on the core's procedural shape zoo (" + std::to_string(glimpse::zoo_categories().size()) +
                                      " categories); with DIR, add its objects of DIR's categories, augmented: learnt, but never what "
                                      "'unknown' measures a cloud against (the recipe that "
                                      "transfers best to other collections: README)");
  train->add_option("--per-category", t.per_category, "zoo objects per category")->capture_default_str()
      ->check(CLI::Range(size_t{1}, size_t{10000}));
  train->add_option("--name", t.name, "model name ([A-Za-z0-9._-], 1-128); with --base, the base's by default")
      ->check(Checked([](const std::string& s) { return ParseModelRef(s + ":latest", /*allow_latest=*/true); }, "NAME"));
  auto* base = train->add_option("--base", t.base,
                                 "grow this stored version: a new version that learns DIR's objects (new categories or more "
                                 "objects) beside the base's, computing the features of DIR's clouds alone; the base's methods "
                                 "and parameters, its views' density; give the view flags the base was trained with")
                   ->check(kModelRef);
  train->add_option("--methods", t.methods, "comma-separated: bok,bog,kgh,vfh,esf,ush,size,fusion (default: the server's, vfh,ush,size,fusion: the fusion, its components and the size baseline; the keypoint methods and esf take about 5 times as long to train)")
      ->check(kMethodList)
      ->excludes(base);
  train->add_option("--description", t.description, "free text stored with the model");
  AddViewOptions(*train, t.protocol, true);
  AddPlacementOptions(*train, t.placement, true, true);
  train->add_option_function<uint64_t>("--train-seed", [&t](const uint64_t& s) { t.train_seed = s; },
                                       "k-means and sampling seed of training (default: the server's)")
      ->excludes(base);
  AddTrainingViewOptions(*train, t);
  train->add_flag("--no-scan-filters", t.no_scan_filters,
                  "the model classifies every point sent as it is (default: it removes stray returns and a floor and "
                  "thins dense scans to its training density)")
      ->excludes(base);
  train->add_flag("--json", t.json, "print the stored model as JSON");
  train->add_flag("-q,--quiet", t.quiet, "no progress on stderr");
  train->callback([&cl] { cl.run = [&cl] { return RunTrain(cl.conn, cl.train); }; });
  return train;
}

void AddClassify(CLI::App& app, CommandLine& cl) {
  auto* classify = app.add_subcommand("classify", "classify point-cloud or mesh files");
  ClassifyOptions& c = cl.classify;
  classify->add_option("FILE", c.files, "clouds (.pcd .ply .xyz, as they are) or meshes (.off .obj .ply .stl, one view each)")->required();
  classify->add_option("--model", c.model, "NAME[:VERSION]")->envname("GLIMPSE_MODEL")->required()->check(kModelRef);
  classify->add_option("--method", c.method, "bok|bog|kgh|vfh|esf|ush|size|fusion (default: the model's)")->check(kMethod);
  classify->add_flag("--json", c.json, "one JSON object per file instead of a table, errors included");
  classify->add_option("--known-acceptance", c.known_acceptance,
                       "operating point of \"unknown\": the share of known clouds to accept, in (0, 1] (default: "
                       "the model's, 0.95 of its held-out training clouds)")
      ->check(kAcceptance);
  auto* view = classify->add_option("--view", c.view, "meshes: which of the paper's 6 viewpoints (azimuth 60*N deg) sees the object")
                   ->capture_default_str()->check(CLI::Range(0, 5))->group("Meshes");
  classify->add_flag("--whole", c.whole, "meshes: the whole sampled cloud instead of a single view")->excludes(view)->group("Meshes");
  AddSensorOption(*classify, c.sensor);
  AddCameraFovOption(*classify, c.camera_fov);
  AddViewOptions(*classify, c.protocol, false);
  AddPlacementOptions(*classify, c.placement, false, true);
  classify->callback([&cl, view] {
    cl.classify.view_given = view->count() > 0 || cl.classify.whole;
    cl.run = [&cl] { return RunClassify(cl.conn, cl.classify); };
  });
}

void AddScene(CLI::App& app, CommandLine& cl) {
  auto* scene = app.add_subcommand("scene", "find every object in one scanner's frame and classify each (ClassifyScene):\n"
                                            "the floor, walls and table tops are removed, the rest split into objects; one\n"
                                            "row per object, nearest first, with its box");
  SceneOptions& s = cl.scene;
  scene->add_option("FRAME", s.file, "a frame: .pcd (organised or not, binary_compressed too), .ply, .xyz; +z up, or its "
                                     "camera's own coordinates with --up floor; no sensor given: at the origin")->required();
  scene->add_option("--model", s.model, "NAME[:VERSION]")->envname("GLIMPSE_MODEL")->required()->check(kModelRef);
  scene->add_option("--method", s.method, "bok|bog|kgh|vfh|esf|ush|size|fusion (default: the model's)")->check(kMethod);
  scene->add_flag("--json", s.json, "the scene as one JSON object: planes, and every object's box and answer");
  scene->add_option("--svg", s.svg, "write a top view of the frame to this file, each object's box labelled");
  scene->add_option("--known-acceptance", s.known_acceptance,
                    "operating point of \"unknown\" for every object, in (0, 1] (default: the model's)")
      ->check(kAcceptance);
  scene->add_option_function<float>("--cluster-tolerance", [&s](const float& m) { s.cluster_tolerance_m = m; },
                                    "metres: points closer than this are one object (server default 0.03)")
      ->check(CLI::Range(0.001f, 1.f))->group("Segmentation");
  scene->add_option_function<uint32_t>("--min-object-points", [&s](const uint32_t& n) { s.min_object_points = n; },
                                       "fewer points: noise, not an object (server default 1000 for a 640 x 480 frame, fewer for a sparser one)")
      ->check(CLI::Range(1u, 1000000u))->group("Segmentation");
  scene->add_option_function<float>("--reference-density", [&s](const float& d) { s.reference_density = d; },
                                    "points per square degree the counts are for: a sparser frame asks for fewer "
                                    "(server default 80; 0: as given)")
      ->check(CLI::Range(0.f, 1e6f))->group("Segmentation");
  scene->add_option_function<float>("--max-object-size", [&s](const float& m) { s.max_object_extent_m = m; },
                                     "metres: a longer box is a wall's remnant, not an object (server default 4)")
      ->check(CLI::Range(0.01f, 50.f))->group("Segmentation");
  AddSensorOption(*scene, s.sensor);  // none in the file: the origin, a camera's own coordinates
  AddCameraFovOption(*scene, s.camera_fov);
  AddPlacementOptions(*scene, s.placement, false, true);
  scene->callback([&cl] { cl.run = [&cl] { return RunScene(cl.conn, cl.scene); }; });
}

CLI::App* AddStream(CLI::App& app, CommandLine& cl) {
  auto* stream = app.add_subcommand("stream", "simulate a scanner: reveal one view in chunks over StreamClassify, or "
                                              "stream a folder of frames from several sensor positions (--frames)");
  StreamOptions& s = cl.stream;
  auto* file = stream->add_option("FILE", s.file, "cloud or mesh file");
  auto* zoo_shape = stream->add_option("--zoo", s.zoo_category, "a zoo shape of this category instead of a file")
                        ->check(CLI::IsMember(glimpse::zoo_categories()));
  file->excludes(zoo_shape);
  stream->add_option("--seed", s.seed, "zoo shape, random order and mesh sampling seed")->capture_default_str();
  stream->add_option("--model", s.model, "NAME[:VERSION]")->envname("GLIMPSE_MODEL")->required()->check(kModelRef);
  stream->add_option("--method", s.method, "bok|bog|kgh|vfh|esf|ush|size|fusion (default: the model's)")->check(kMethod);
  auto* chunks = stream->add_option("--chunks", s.chunks, "number of chunks")->capture_default_str()
                     ->check(CLI::Range(size_t{1}, size_t{100000}));
  stream->add_option("--chunk-points", s.chunk_points, "points per chunk instead of --chunks")
      ->check(CLI::Range(size_t{1}, size_t{1000000}))->excludes(chunks);
  stream->add_option("--order", s.order, "reveal order: top-down (the paper's), random, sweep")
      ->capture_default_str()->check(kOrder);
  stream->add_option("--rate", s.rate_hz, "chunks per second, 0 = as fast as possible")->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  auto* stream_view = stream->add_option_function<int>("--view", [&s](const int& v) { s.viewpoint = v; },
                                   "which of the paper's 6 viewpoints (azimuth 60*N deg) sees the object: meshes and zoo "
                                   "shapes [0]; a cloud file streams as it is unless given")
      ->check(CLI::Range(0, 5));
  AddSensorOption(*stream, s.sensor)->excludes(stream_view);
  AddCameraFovOption(*stream, s.camera_fov)->excludes(stream_view);
  auto* frames = stream->add_option("--frames", s.frames_dir,
                                    "a folder of frames (.pcd/.ply/...), each from its own sensor position (its file's "
                                    "VIEWPOINT or glimpse_sensor comment, or DIR/poses.csv: file,x,y,z for points in the "
                                    "common frame, file,x,y,z,qw,qx,qy,qz for points in the sensor's frame), streamed in "
                                    "natural name order, one chunk per frame (--chunk-points cuts a frame into several)")
                     ->check(CLI::ExistingDirectory);
  frames->excludes(file)->excludes(zoo_shape)->excludes(stream_view)->excludes(chunks)->excludes("--order")
      ->excludes("--sensor")->excludes("--camera-fov");
  stream->add_option_function<std::string>("--track", [&s](const std::string& t) { s.track = *ParseTrackTarget(t); },
                                           "follow one object among others through --frames: 'nearest' (nearest the "
                                           "camera's axis), X,Y,Z (the object at that point) or X0,Y0,Z0,X1,Y1,Z1 (in "
                                           "that box); each frame is sent whole and split into objects by the server")
      ->check(Checked(ParseTrackTarget, "nearest|X,Y,Z|X0,Y0,Z0,X1,Y1,Z1"))->needs(frames)->excludes("--chunk-points");
  stream->add_flag("--json", s.json, "one JSON object per decision");
  stream->add_option("--known-acceptance", s.known_acceptance,
                     "operating point of \"unknown\": the share of known clouds to accept, in (0, 1] (default: "
                     "the model's)")
      ->check(kAcceptance);
  stream->add_option("--mesh-points", s.protocol.points, "points sampled on a mesh's surface")
      ->capture_default_str()->check(CLI::Range(size_t{0}, size_t{5'000'000}))->group("Meshes");
  AddPlacementOptions(*stream, s.placement, false, true);
  stream->callback([&cl] { cl.run = [&cl] { return RunStream(cl.conn, cl.stream); }; });
  return stream;
}

void AddEvaluate(CLI::App& app, CommandLine& cl) {
  auto* evaluate = app.add_subcommand("evaluate", "classify the protocol's views of every mesh of a labelled folder\n"
                                                  "DIR/<category>/<meshes> (made exactly as glimpse-lab makes them) and report\n"
                                                  "accuracy, balanced accuracy, the confusion table and the misclassified objects");
  EvaluateOptions& e = cl.evaluate;
  evaluate->add_option("DIR", e.dir, "folder of category folders of meshes (its manifest applies as in train)")
      ->required()->check(CLI::ExistingDirectory);
  evaluate->add_option("--model", e.model, "NAME[:VERSION]")->envname("GLIMPSE_MODEL")->required()->check(kModelRef);
  evaluate->add_option("--method", e.method, "bok|bog|kgh|vfh|esf|ush|size|fusion (default: the model's)")->check(kMethod);
  evaluate->add_option("--stages", e.stages, "comma-separated: full, N (the top N % of the object's cloud)")
      ->capture_default_str()->check(Checked(ParseStages, "full,10,20"));
  evaluate->add_option("--max-per-category", e.max_per_category, "at most N objects per category (0: all)")
      ->capture_default_str();
  evaluate->add_option("--batch", e.batch_clouds, "clouds per ClassifyBatch call")->capture_default_str()
      ->check(CLI::Range(size_t{1}, size_t{256}));
  evaluate->add_flag("--json", e.json, "the report as one JSON object");
  evaluate->add_flag("-q,--quiet", e.quiet, "no progress on stderr");
  AddViewOptions(*evaluate, e.protocol, true);
  AddPlacementOptions(*evaluate, e.placement, true, false);
  evaluate->callback([&cl] { cl.run = [&cl] { return RunEvaluate(cl.conn, cl.evaluate); }; });
}

int Main(int argc, char** argv) {
  CLI::App app{"glimpse: recognise an object's category from a partial point cloud, with a Glimpse server.\n"
               "Exit status: 0 ok, 1 error, 2 usage.",
               "glimpse"};
  app.set_version_flag("--version", "glimpse 0.1.0");
  app.require_subcommand(1);
  app.fallthrough();  // connection options may also follow the subcommand
  CommandLine cl;
  AddConnectionOptions(app, cl.conn);
  AddHealth(app, cl);
  AddModels(app, cl);
  const CLI::App* train = AddTrain(app, cl);
  AddClassify(app, cl);
  AddScene(app, cl);
  const CLI::App* stream = AddStream(app, cl);
  AddEvaluate(app, cl);
  try {
    app.parse(argc, argv);
    if (train->parsed() && cl.train.dir.empty() && !cl.train.zoo) throw CLI::RequiredError("train needs DIR or --zoo");
    if (stream->parsed() && cl.stream.file.empty() && cl.stream.zoo_category.empty() && cl.stream.frames_dir.empty())
      throw CLI::RequiredError("stream needs FILE, --zoo CATEGORY or --frames DIR");
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints help/version (code 0) or the error
    return code == 0 ? kExitOk : kExitUsage;
  }
  return cl.run ? cl.run() : kExitUsage;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "glimpse: fatal: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "glimpse: fatal: unknown error\n");
  }
  return kExitError;
}

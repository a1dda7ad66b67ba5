// glimpse-lab eval: the paper's evaluation protocol (sec. 3.4, 4, 5) on the SHREC 2007 meshes or the
// procedural zoo, written as a report (report.md, decisions.csv, evolution SVGs). The protocol lives
// in core (evaluation.h); this file only turns flags into EvalParams and shows progress.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <numbers>
#include <sstream>

#include "glimpse/evaluation.h"
#include "lab_eval.h"

namespace glimpse::lab {

namespace {

struct EvalOptions {
  std::string data;
  std::string train;
  std::string test;
  std::string size_blind = "fusion";
  std::string also_train;
  float tilt = -1;
  size_t zoo = 0;
  std::string points = "6000";
  size_t views = 6;
  int folds = 5;
  std::string methods = "bok,bog,kgh,vfh,esf,ush,size,fusion";
  std::string train_on = "partial";
  std::string train_prefixes = "0.15,0.25,0.35,0.5,0.7";
  std::string train_elevations;  // extra training-only views, degrees above the horizon
  std::string decision = "nearest";
  std::string fusion_of;
  int neighbours = 0;
  double pca_variance = 0;
  int pca_dims = 0;
  int threads = 0;
  uint64_t seed = 42;
  std::string out = "out/eval";
  bool quick = false;
  size_t max_objects = 0;
  size_t explore_step = 5;
  float cut_margin = 1.5f;
  std::string stages = "full,10kp,25kp,55kp,10%,20%";
  double stream_chunk = 0.02;
  std::string sensor = "ideal";
  float distance = 2.f;
  float elevation = 30.f;
  float scan_tilt = 0.f;
  bool floor = false;
  double outliers = 0;
  std::string matrix = "small";
  std::string preset;
  // Keypoints (sec. 2.2, 3.2.1-3.2.2); negative: the recogniser's default.
  int support_neighbours = -1;
  int min_neighbours = -1;
  float keypoint_cap = -1;     // rho1 cap in support radii, 0: none
  float claim_min = -1;        // claim radius at least this x r, 0: rho1 alone
  float boundary_band = -1;    // in support radii, 0: boundary points only
  float boundary_gap = -1;     // degrees
  float boundary_radius = -1;  // the boundary test's neighbourhood, in support radii
  float descriptor_scale = -1; // descriptors over rho1 clamped to [r, this x r]; 0: over r
  std::string keypoint_response;
  int normalise_up_to = -1;
  std::string default_method;
  bool keypoint_ablation = false;
  int soft_words = 0;
  size_t matrix_views = 0;  // 0: 1 per object for the small matrix (the default run stays within 5 minutes), 2 for full
};

// --preset paper: the paper's settings (sec. 3.2-4) for every flag not given on the command line.
Status apply_preset(EvalOptions& o, const CLI::App& cmd) {
  if (o.preset.empty()) return {};
  if (o.preset != "paper") return invalid_argument("--preset must be 'paper', not '" + o.preset + "'");
  auto unset = [&](const char* flag) { return cmd.get_option(flag)->count() == 0; };
  if (unset("--points")) o.points = "vertices";                  // sec. 3.4: the meshes' vertices
  if (unset("--methods")) o.methods = "bok,bog,kgh,vfh";          // sec. 3.1, 3.2.6
  if (unset("--default-method")) o.default_method = "bok";        // the category-change figures are BoK's
  if (unset("--train-on")) o.train_on = "full";                   // trained on whole views
  if (unset("--train-tilt")) o.tilt = 0;                          // as given
  if (unset("--decision")) o.decision = "nearest-centre";         // sec. 4: one centre per category, L1
  if (unset("--pca-variance")) o.pca_variance = -1;               // ... on the histograms (BoG: 65 dims)
  if (unset("--normalise-up-to")) o.normalise_up_to = 25;         // sec. 4: normalise early, not later
  // Keypoints (sec. 2.2, 3.2.1-3.2.2); the choices the text leaves open settled by the keypoint ablation.
  if (unset("--support-neighbours")) o.support_neighbours = 6;    // sec. 3.2.1: r as small as the density
  if (unset("--min-neighbours")) o.min_neighbours = 6;            //   allows: a quadric needs 6 points
  if (unset("--keypoint-cap")) o.keypoint_cap = 0;                // sec. 2.2: no cap on rho1
  if (unset("--claim-min")) o.claim_min = 0;                      // each keypoint claims rho1 (eq. 3)
  if (unset("--boundary-radius")) o.boundary_radius = 2;          // vertex spacing is irregular: test over 2 r
  if (unset("--boundary-band")) o.boundary_band = 0.25f;          // sec. 3.2.2: "in a given radius"
  if (unset("--descriptor-scale")) o.descriptor_scale = 8;        // described at rho1 (up to 8 r), not at r
  if (unset("--stream-chunk")) o.stream_chunk = 0;                // no streams in the paper
  if (unset("--matrix")) o.matrix = "none";
  if (unset("--size-blind")) o.size_blind = "none";
  return {};
}

Expected<EvalParams> params_from(const EvalOptions& o) {
  EvalParams p;
  if (o.points == "vertices") {
    p.points_per_object = 0;
  } else {
    char* end = nullptr;
    const long n = std::strtol(o.points.c_str(), &end, 10);
    if (n <= 0 || *end) return invalid_argument("--points must be 'vertices' or a positive count, not '" + o.points + "'");
    p.points_per_object = static_cast<size_t>(n);
  }
  p.views_per_object = o.views;
  {
    std::stringstream list(o.train_elevations);
    for (std::string item; std::getline(list, item, ',');) {
      char* end = nullptr;
      const double e = std::strtod(item.c_str(), &end);
      if (item.empty() || *end || !(e >= -90 && e <= 90))
        return invalid_argument("--train-elevations takes degrees in [-90, 90], not '" + item + "'");
      p.train_elevations_deg.push_back(float(e));
    }
  }
  p.folds = o.folds;
  p.methods.clear();
  std::stringstream list(o.methods);
  for (std::string name; std::getline(list, name, ',');) {
    auto m = parse_method(name);
    if (!m.ok()) return m.error();
    p.methods.push_back(*m);
  }
  if (o.train_on != "partial" && o.train_on != "full")
    return invalid_argument("--train-on must be 'full' or 'partial', not '" + o.train_on + "'");
  p.train.partial_prefixes.clear();
  std::stringstream fractions(o.train_prefixes);
  for (std::string item; std::getline(fractions, item, ',');) {
    char* end = nullptr;
    const double f = std::strtod(item.c_str(), &end);
    if (item.empty() || *end || !(f > 0 && f < 1))
      return invalid_argument("--train-prefixes takes fractions in (0, 1), not '" + item + "'");
    if (o.train_on == "partial") p.train.partial_prefixes.push_back(f);
  }
  if (o.decision == "nearest-centre") p.train.decision.kind = DecisionRule::kNearestCentre;
  else if (o.decision == "centres") p.train.decision.kind = DecisionRule::kCentres;
  else if (o.decision == "knn") p.train.decision.kind = DecisionRule::kNearestNeighbours;
  else if (o.decision == "nearest") p.train.decision.kind = DecisionRule::kNearestReference;
  else return invalid_argument("--decision must be nearest-centre, centres, knn or nearest, not '" + o.decision + "'");
  if (!o.fusion_of.empty()) {
    p.train.fusion_of.clear();
    std::stringstream parts(o.fusion_of);
    for (std::string name; std::getline(parts, name, ',');) {
      auto m = parse_method(name);
      if (!m.ok()) return m.error();
      if (*m == MethodId::kFusion) return invalid_argument("--fusion-of: fusion cannot be its own component");
      p.train.fusion_of.push_back(*m);
    }
  }
  if (o.neighbours > 0) p.train.decision.neighbours = o.neighbours;
  if (o.tilt >= 0) p.train.tilt_deg = o.tilt;
  if (o.pca_variance > 0) p.train.decision.pca_explained_variance = o.pca_variance;
  if (o.pca_dims > 0) p.train.decision.max_pca_dims = o.pca_dims;
  p.threads = o.threads;
  p.seed = o.seed;
  p.explore_step = o.explore_step;
  p.stages.clear();
  for (const std::string& name : [&] {
         std::vector<std::string> v;
         std::stringstream list(o.stages);
         for (std::string item; std::getline(list, item, ',');) v.push_back(item);
         return v;
       }()) {
    char* end = nullptr;
    const double x = std::strtod(name.c_str(), &end);
    if (name == "full") p.stages.push_back({StageKind::kFull, 0});
    else if (end && std::string(end) == "kp" && x >= 1) p.stages.push_back({StageKind::kKeypoints, x});
    else if (end && std::string(end) == "%" && x > 0 && x <= 100) p.stages.push_back({StageKind::kFraction, x / 100});
    else return invalid_argument("--stages takes full, Nkp and N% items, not '" + name + "'");
  }
  if (!std::any_of(p.stages.begin(), p.stages.end(), [](const Stage& s) { return s.kind == StageKind::kKeypoints; }))
    p.explore_max_keypoints = 0;
  if (!(o.stream_chunk >= 0 && o.stream_chunk < 1)) return invalid_argument("--stream-chunk must be in [0, 1)");
  p.stream_chunk_fraction = o.stream_chunk;
  p.cut_margin_supports = o.cut_margin;
  auto sensor = parse_sensor(o.sensor);
  if (!sensor.ok()) return Error{sensor.error().code, "--sensor: " + sensor.error().message};
  ScanCondition& c = p.test_condition;
  c.sensor = *sensor;
  if (c.sensor != SensorKind::kIdeal) c.distance_m = o.distance, c.elevation_deg = o.elevation;
  if (!(o.distance > 0)) return invalid_argument("--distance must be positive metres");
  if (!(o.elevation >= -90 && o.elevation <= 90)) return invalid_argument("--elevation must be in [-90, 90] degrees");
  if (!(o.scan_tilt >= 0 && o.scan_tilt <= 90)) return invalid_argument("--tilt must be in [0, 90] degrees");
  if (!(o.outliers >= 0 && o.outliers <= 1)) return invalid_argument("--outliers must be a fraction in [0, 1]");
  if (o.floor && c.sensor == SensorKind::kIdeal) return invalid_argument("--floor needs a sensor (--sensor depth|lidar)");
  c.tilt_deg = o.scan_tilt, c.floor = o.floor, c.outliers = o.outliers;
  if (o.matrix != "none" && o.matrix != "small" && o.matrix != "full")
    return invalid_argument("--matrix must be none, small or full, not '" + o.matrix + "'");
  p.matrix = robustness_conditions(o.matrix);
  p.matrix_views_per_object = o.matrix_views ? o.matrix_views : o.matrix == "full" ? 2 : 1;
  FeatureParams& fp = p.train.features;
  if (o.support_neighbours >= 0) {
    if (o.support_neighbours < 3) return invalid_argument("--support-neighbours must be at least 3");
    fp.surface.support_neighbours = o.support_neighbours;
  }
  if (o.min_neighbours >= 0) {
    if (o.min_neighbours < 6) return invalid_argument("--min-neighbours must be at least 6 (a quadric has 6 coefficients)");
    fp.surface.min_neighbours = o.min_neighbours;
  }
  if (o.keypoint_cap >= 0) fp.keypoints.max_radius_supports = o.keypoint_cap;
  if (o.claim_min >= 0) fp.keypoints.claim_min_supports = o.claim_min;
  if (o.boundary_band >= 0) fp.keypoints.boundary_band_supports = o.boundary_band;
  if (o.descriptor_scale >= 0) fp.descriptor.characteristic_scale_supports = o.descriptor_scale;
  if (o.boundary_radius >= 0) {
    if (!(o.boundary_radius > 0)) return invalid_argument("--boundary-radius must be positive (support radii)");
    fp.keypoints.boundary_radius_supports = o.boundary_radius;
  }
  if (o.boundary_gap >= 0) {
    if (!(o.boundary_gap > 0 && o.boundary_gap < 360)) return invalid_argument("--boundary-gap must be in (0, 360) degrees");
    fp.keypoints.boundary_gap_rad = o.boundary_gap * std::numbers::pi_v<float> / 180;
  }
  if (o.keypoint_response == "lambda-min") fp.keypoints.response = KeypointResponse::kLambdaMin;
  else if (o.keypoint_response == "harris") fp.keypoints.response = KeypointResponse::kHarris;
  else if (!o.keypoint_response.empty())
    return invalid_argument("--keypoint-response must be lambda-min or harris, not '" + o.keypoint_response + "'");
  if (o.normalise_up_to >= 0) p.train.normalise_up_to_keypoints = o.normalise_up_to;
  if (o.soft_words < 0) return invalid_argument("--soft-words must be 1 or more");
  if (o.soft_words > 0) p.train.bok_soft_words = o.soft_words;
  if (o.pca_variance < 0) p.train.decision.pca_explained_variance = 0;  // none: L1 on the histograms
  if (!o.default_method.empty()) {
    auto m = parse_method(o.default_method);
    if (!m.ok()) return Error{m.error().code, "--default-method: " + m.error().message};
    if (std::find(p.methods.begin(), p.methods.end(), *m) == p.methods.end())
      return invalid_argument("--default-method " + o.default_method + " is not among --methods");
    p.train.default_method = *m;
  }
  if (o.quick) {  // CI: 3 views per object, a coarser exploration grid
    p.views_per_object = std::min<size_t>(p.views_per_object, 3);
    p.explore_step = std::max<size_t>(p.explore_step, 10);
    p.matrix_views_per_object = 1;
  }
  return p;
}


// The objects of every folder in `dirs`, each given `role`.
Expected<std::vector<EvalObject>> load_sources(const std::vector<std::string>& dirs, EvalRole role, uint64_t seed,
                                               size_t max_objects, int threads) {
  std::vector<EvalObject> all;
  for (const std::string& dir : dirs) {
    Expected<std::vector<EvalObject>> loaded = std::vector<EvalObject>{};
    if (dir.rfind("zoo:", 0) == 0) {  // the procedural zoo as a source: zoo:N objects per category
      const long n = std::strtol(dir.c_str() + 4, nullptr, 10);
      if (n <= 0) return invalid_argument("'" + dir + "': want zoo:N with N objects per category");
      std::fprintf(stderr, "making the zoo: %ld objects per category ...\n", n);
      loaded = zoo_objects(static_cast<size_t>(n), seed);
    } else {
      std::fprintf(stderr, "loading %s ...\n", dir.c_str());
      loaded = load_dataset_objects(dir, seed, max_objects, threads);
    }
    if (!loaded.ok()) return loaded.error();
    for (EvalObject& o : *loaded) {
      o.role = role;
      all.push_back(std::move(o));
    }
  }
  return all;
}

int run_eval(const EvalOptions& o) {
  auto params = params_from(o);
  if (!params.ok()) {
    std::fprintf(stderr, "glimpse-lab eval: %s\n", params.error().message.c_str());
    return 2;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const size_t max_objects = o.quick && o.max_objects == 0 ? 8 : o.max_objects;
  std::vector<EvalObject> objects;
  std::string source;
  if (!o.data.empty() || !o.train.empty()) {
    const bool cross = !o.train.empty();
    auto first = load_sources(split_list(cross ? o.train : o.data), cross ? EvalRole::kTrainOnly : EvalRole::kCrossValidate,
                              params->seed, max_objects, params->threads);
    if (!first.ok()) {
      std::fprintf(stderr, "glimpse-lab eval: %s\n", first.error().message.c_str());
      return 1;
    }
    objects = std::move(*first);
    source = "meshes in " + (cross ? o.train : o.data);
    if (!o.also_train.empty()) {
      auto extra = load_sources(split_list(o.also_train), EvalRole::kTrainOnly, params->seed, max_objects, params->threads);
      if (!extra.ok()) {
        std::fprintf(stderr, "glimpse-lab eval: --also-train: %s\n", extra.error().message.c_str());
        return 1;
      }
      for (EvalObject& x : *extra) objects.push_back(std::move(x));
      source += " (also trained on " + o.also_train + ")";
    }
    if (cross) {
      auto second = load_sources(split_list(o.test), EvalRole::kTestOnly, params->seed, max_objects, params->threads);
      if (!second.ok()) {
        std::fprintf(stderr, "glimpse-lab eval: %s\n", second.error().message.c_str());
        return 1;
      }
      for (EvalObject& x : *second) objects.push_back(std::move(x));
      source = "trained on " + o.train + (o.also_train.empty() ? "" : "," + o.also_train) + ", tested on " + o.test;
    }
  } else {
    const size_t n = max_objects ? std::min(o.zoo, max_objects) : o.zoo;
    std::fprintf(stderr, "making the zoo: %zu objects per category ...\n", n);
    objects = zoo_objects(n, params->seed);
    source = "procedural zoo (make_zoo, seed " + std::to_string(params->seed) + ")";
  }
  const double load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  ProgressBar bar;
  auto result = run_evaluation(objects, *params, source, [&bar](const EvalProgress& p) { bar(p); });
  if (!result.ok()) {
    bar({"done", 1, 1});
    std::fprintf(stderr, "glimpse-lab eval: %s\n", result.error().message.c_str());
    return 1;
  }
  if (o.size_blind != "none")
    if (Status s = size_blind_ablation(*result, objects, *params, o.size_blind, bar); !s.ok()) {
      std::fprintf(stderr, "glimpse-lab eval: --size-blind: %s\n", s.error().message.c_str());
      return 2;
    }
  if (o.keypoint_ablation)
    if (Status s = keypoint_ablation(*result, objects, *params, bar); !s.ok()) {
      std::fprintf(stderr, "glimpse-lab eval: --keypoint-ablation: %s\n", s.error().message.c_str());
      return 2;
    }
  bar({"done", 1, 1});
  result->timings.insert(result->timings.begin(), {"load objects", load_seconds, std::to_string(objects.size()) + " meshes"});
  result->total_seconds += load_seconds;
  if (Status s = write_report(*result, o.out); !s.ok()) {
    std::fprintf(stderr, "glimpse-lab eval: %s\n", s.error().message.c_str());
    return 1;
  }
  for (const PhaseTiming& t : result->timings)
    std::fprintf(stderr, "  %-24s %7.1f s  %s\n", t.phase.c_str(), t.seconds, t.detail.c_str());
  if (result->cross_source)
    std::printf("accuracy %% (paper in brackets), trained on %s, tested on %zu objects of %s:\n%s", o.train.c_str(),
                result->streams.empty() ? size_t{0} : result->streams.size() / params->views_per_object, o.test.c_str(),
                summary_table(*result).c_str());
  else
    std::printf("accuracy %% (paper in brackets), %zu objects, %d folds:\n%s", objects.size(), params->folds,
                summary_table(*result).c_str());
  std::printf("category changes (%s), finally correct / incorrect:", method_name(result->change_method));
  for (const ChangeRow& c : result->changes)
    std::printf("  <=%zu kp %.2f / %.2f", c.up_to_keypoints, c.mean_correct, c.mean_incorrect);
  std::printf("\ntime %.1f s on %d threads\n", result->total_seconds, result->threads);
  std::printf("report: %s\n", (std::filesystem::path(o.out) / "report.md").string().c_str());
  return 0;
}

}  // namespace

void add_eval_command(CLI::App& app) {
  auto o = std::make_shared<EvalOptions>();
  CLI::App* cmd = app.add_subcommand("eval", "run the paper's evaluation protocol and write a report");
  auto* data = cmd->add_option("--data", o->data,
                               "dataset folders DIR[,DIR...] (DIR/<category>/<mesh>, e.g. SHREC 2007): cross-validation "
                               "over the union, by object");
  auto* train = cmd->add_option("--train", o->train, "cross-source: train on every object of these folders DIR[,DIR...]");
  auto* test = cmd->add_option("--test", o->test, "cross-source: test on every view of these folders DIR[,DIR...]");
  auto* zoo = cmd->add_option("--zoo", o->zoo, "use the procedural zoo with N objects per category instead");
  data->excludes(zoo)->excludes(train)->excludes(test);
  zoo->excludes(data)->excludes(train)->excludes(test);
  train->needs(test);
  test->needs(train);
  cmd->add_option("--also-train", o->also_train,
                  "extra training-only sources DIR[,DIR...] or zoo:N (the procedural zoo, N per category), learnt by "
                  "every model and never tested");
  cmd->add_option("--train-tilt", o->tilt, "training views turned by a random tilt of up to DEG degrees (default: the recogniser's)");
  cmd->add_option("--size-blind", o->size_blind,
                  "methods of the size-blind ablation (every object 1 m tall, train and test), or 'none'")
      ->capture_default_str();
  cmd->add_option("--points", o->points,
                  "object cloud: 'vertices' (the paper) or N area-weighted samples per object (a sensor at 3x the "
                  "bounding radius sees about the same number of points whatever the object's size)")
      ->capture_default_str();
  cmd->add_option("--views", o->views, "views per object (1-6, evenly spaced of the paper's 6)")->capture_default_str();
  cmd->add_option("--train-elevations", o->train_elevations,
                  "training-only views besides the tested ones: the same azimuths from these elevations, degrees "
                  "above the horizon, comma-separated (tested views stay at the paper's 30; e.g. 0,15 for cameras "
                  "mounted low)");
  cmd->add_option("--folds", o->folds, "cross-validation folds (by object, stratified)")->capture_default_str();
  cmd->add_option("--methods", o->methods, "comma-separated: bok,bog,kgh,vfh,esf,ush,size,fusion")->capture_default_str();
  cmd->add_option("--train-on", o->train_on,
                  "full: full views only (the paper); partial: plus their top-down prefixes (--train-prefixes)")
      ->capture_default_str();
  cmd->add_option("--train-prefixes", o->train_prefixes,
                  "with --train-on partial: comma-separated fractions of each training view's points")
      ->capture_default_str();
  cmd->add_option("--decision", o->decision, "nearest-centre (the paper), centres, knn or nearest (every training vector a reference)")->capture_default_str();
  cmd->add_option("--fusion-of", o->fusion_of, "comma-separated components of fusion (default: the recogniser's)");
  cmd->add_option("--neighbours", o->neighbours, "k of the k-NN decision (0: the recogniser's default)");
  cmd->add_option("--pca-variance", o->pca_variance,
                  "explained variance the decision stage's PCA keeps (0: default; negative: no PCA, L1 on the histograms)");
  cmd->add_option("--pca-dims", o->pca_dims, "at most this many PCA dimensions in the decision stage (0: default)");
  cmd->add_option("--threads", o->threads, "threads (0: all cores); results do not depend on it")->capture_default_str();
  cmd->add_option("--seed", o->seed, "seed of sizes, samples, folds, codebooks")->capture_default_str();
  cmd->add_option("--out", o->out, "report folder")->capture_default_str();
  cmd->add_flag("--quick", o->quick, "CI size: at most 8 objects per category, 3 views, exploration every 10 keypoints");
  cmd->add_option("--max-objects", o->max_objects, "at most N objects per category (0: all)")->capture_default_str();
  cmd->add_option("--explore-step", o->explore_step, "keypoint step of the exploration grid (1: the paper's)")
      ->capture_default_str();
  cmd->add_option("--stages", o->stages, "comma-separated stages: full, Nkp (N visible keypoints), N% (of the full cloud)")
      ->capture_default_str();
  cmd->add_option("--stream-chunk", o->stream_chunk,
                  "stream every test view in chunks of this fraction of the full cloud (0: no streaming)")
      ->capture_default_str();
  cmd->add_option("--sensor", o->sensor,
                  "test views from: ideal (HPR on samples, the paper's), depth (Kinect-class camera) or lidar "
                  "(16 beams), cast against the mesh; training views stay ideal")
      ->capture_default_str();
  cmd->add_option("--distance", o->distance, "depth/lidar: metres from the sensor to the object's centre")
      ->capture_default_str();
  cmd->add_option("--elevation", o->elevation, "depth/lidar: degrees above the horizon")->capture_default_str();
  cmd->add_option("--tilt", o->scan_tilt, "test views' up off by up to DEG degrees (random direction)")
      ->capture_default_str();
  cmd->add_flag("--floor", o->floor, "depth/lidar: a floor patch under the object, removed by the ground filter");
  cmd->add_option("--outliers", o->outliers, "stray points added to each test view, x its size")->capture_default_str();
  cmd->add_option("--matrix", o->matrix, "robustness matrix: none, small (default run) or full")->capture_default_str();
  cmd->add_option("--matrix-views", o->matrix_views,
                  "views per tested object in the robustness matrix (0: 1 for small, 2 for full)")
      ->capture_default_str();
  cmd->add_option("--cut-margin", o->cut_margin, "keypoint stage cut below the k-th keypoint, in support radii")
      ->capture_default_str();
  cmd->add_option("--preset", o->preset,
                  "paper: the paper's settings for every flag not given (mesh vertices, full-view training, "
                  "BoK/BoG/KGH/VFH, one centre per category with L1 on the histograms, r from 6 neighbours, no "
                  "rho1 cap, claims of rho1, boundary test over 2 r with a band of r/4, descriptors at rho1 up to "
                  "8 r, normalised up to 25 keypoints)");
  cmd->add_option("--support-neighbours", o->support_neighbours,
                  "support radius r = median distance to this nearest neighbour (default 30)");
  cmd->add_option("--min-neighbours", o->min_neighbours, "fewer neighbours within r: no surface (default 8)");
  cmd->add_option("--keypoint-cap", o->keypoint_cap, "keypoints need rho1 <= this x r; 0: no cap (default 8)");
  cmd->add_option("--claim-min", o->claim_min, "a keypoint claims max(rho1, this x r); 0: rho1 (default 1)");
  cmd->add_option("--boundary-band", o->boundary_band,
                  "no keypoint within this x r of a view's boundary point; 0: boundary points only (default 1)");
  cmd->add_option("--descriptor-scale", o->descriptor_scale,
                  "describe each keypoint over its rho1 clamped to [r, this x r]; 0: over r (default)");
  cmd->add_option("--boundary-radius", o->boundary_radius,
                  "the boundary test looks at neighbours within this x r (default 1)");
  cmd->add_option("--boundary-gap", o->boundary_gap, "boundary point: an angular gap wider than DEG (default 90)");
  cmd->add_option("--keypoint-response", o->keypoint_response,
                  "lambda-min (the paper: smaller principal Harris curvature) or harris (det - k tr^2, local maxima)");
  cmd->add_option("--normalise-up-to", o->normalise_up_to,
                  "keypoint histograms divided by their count up to N keypoints and by N's after (sec. 4); 0: always");
  cmd->add_option("--soft-words", o->soft_words,
                  "BoK: each keypoint shared among its N nearest words (default 1: one word, the paper)");
  cmd->add_option("--default-method", o->default_method,
                  "the method of the category changes and streams (default: the recogniser's, fusion)");
  cmd->add_flag("--keypoint-ablation", o->keypoint_ablation,
                "also re-run the keypoint methods with one keypoint or decision setting changed at a time (rho1 cap, "
                "claim radius, boundary band, r, vertices/samples, response, normalisation, PCA, decision, prefixes)");
  cmd->callback([o, cmd] {
    if (Status s = apply_preset(*o, *cmd); !s.ok()) {
      std::fprintf(stderr, "glimpse-lab eval: %s\n", s.error().message.c_str());
      throw CLI::RuntimeError(2);
    }
    if (o->data.empty() && o->train.empty() && o->zoo == 0) {
      std::fprintf(stderr, "glimpse-lab eval: give --data DIR, --train DIR --test DIR, or --zoo N\n%s", cmd->help().c_str());
      throw CLI::RuntimeError(2);
    }
    if (int rc = run_eval(*o); rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace glimpse::lab

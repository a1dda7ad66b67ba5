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
#include <sstream>

#include "glimpse/evaluation.h"

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
  size_t matrix_views = 0;  // 0: 1 per object for the small matrix (the default run stays within 5 minutes), 2 for full
};

// A progress bar on stderr; plain lines (every 10 %) when stderr is not a terminal.
class ProgressBar {
 public:
  ProgressBar() : tty_(isatty(STDERR_FILENO) != 0) {}
  ~ProgressBar() { finish_line(); }

  void operator()(const EvalProgress& p) {
    if (p.phase != phase_) {
      finish_line();
      phase_ = p.phase;
      last_decile_ = -1;
      start_ = std::chrono::steady_clock::now();
    }
    const double frac = p.total ? double(p.done) / double(p.total) : 1.0;
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (tty_) {
      const int width = 30, filled = static_cast<int>(frac * width);
      std::fprintf(stderr, "\r%-28s [%s%s] %zu/%zu %5.1fs", phase_.c_str(), std::string(filled, '#').c_str(),
                   std::string(width - filled, '.').c_str(), p.done, p.total, secs);
      open_ = true;
    } else if (int decile = static_cast<int>(frac * 10); decile > last_decile_) {
      last_decile_ = decile;
      std::fprintf(stderr, "%s: %zu/%zu (%.1fs)\n", phase_.c_str(), p.done, p.total, secs);
    }
    std::fflush(stderr);
  }

 private:
  void finish_line() {
    if (open_) std::fputc('\n', stderr);
    open_ = false;
  }
  bool tty_;
  bool open_ = false;
  std::string phase_;
  int last_decile_ = -1;
  std::chrono::steady_clock::time_point start_;
};

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
  if (o.quick) {  // CI: 3 views per object, a coarser exploration grid
    p.views_per_object = std::min<size_t>(p.views_per_object, 3);
    p.explore_step = std::max<size_t>(p.explore_step, 10);
    p.matrix_views_per_object = 1;
  }
  return p;
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
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

// The size-blind ablation (every object 1 m tall, train and test) of `methods`: the same protocol
// without streams or the keypoint exploration, its accuracies added to `result` beside the real ones.
Status size_blind_ablation(EvalResult& result, const std::vector<EvalObject>& objects, const EvalParams& params,
                           const std::string& methods, ProgressBar& bar) {
  EvalParams p = params;
  p.methods.clear();
  for (const std::string& name : split_list(methods)) {
    auto m = parse_method(name);
    if (!m.ok()) return m.error();
    p.methods.push_back(*m);
  }
  if (p.methods.empty()) return {};
  p.stream_chunk_fraction = 0;
  p.explore_max_keypoints = 0;
  p.matrix.clear();
  const bool keypoints = std::any_of(p.methods.begin(), p.methods.end(), [](MethodId m) {
    return m == MethodId::kBoK || m == MethodId::kBoG || m == MethodId::kKGH;
  });
  if (!keypoints) std::erase_if(p.stages, [](const Stage& s) { return s.kind == StageKind::kKeypoints; });
  const auto t0 = std::chrono::steady_clock::now();
  auto blind = run_evaluation(common_height(objects, 1.0f), p, result.source + ", every object 1 m tall",
                              [&bar](const EvalProgress& e) { bar({"size-blind: " + e.phase, e.done, e.total}); });
  if (!blind.ok()) return blind.error();
  add_ablation(result, *blind, "size-blind: every object 1 m tall, train and test");
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  result.timings.push_back({"size-blind ablation", secs, std::to_string(blind->decisions.size()) + " decisions"});
  result.total_seconds += secs;
  return {};
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
  cmd->add_option("--pca-variance", o->pca_variance, "explained variance the decision stage's PCA keeps (0: default)");
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
  cmd->callback([o, cmd] {
    if (o->data.empty() && o->train.empty() && o->zoo == 0) {
      std::fprintf(stderr, "glimpse-lab eval: give --data DIR, --train DIR --test DIR, or --zoo N\n%s", cmd->help().c_str());
      throw CLI::RuntimeError(2);
    }
    if (int rc = run_eval(*o); rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace glimpse::lab

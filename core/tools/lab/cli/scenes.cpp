// glimpse-lab scenes: synthetic scenes of a test source's objects, segmented by segment_scene, matched to
// the truth and recognised by a model of a training source, written as a report (report.md, scenes.json,
// objects.csv). The scenes, their scoring and the training live in the lab library (glimpse/lab/scenes.h);
// this file declares the flags, loads the objects and shows progress.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>
#include <set>

#include "eval.h"
#include "glimpse/lab/scenes.h"

namespace glimpse::lab {

namespace {

struct ScenesOptions {
  std::string train, also_train, test;
  size_t test_zoo = 0;
  bool detect_only = false;
  std::string model_file, save_model;  // --model: learnt before, not trained again; --save-model: where to keep it
  std::string tuned_on = "segment_scene's defaults";
  std::string out = "out/scenes";
  EvalOptions eval;  // the training flags eval shares: --methods, --points, --views, --train-sensors, --seed, --threads
  ScenesParams scenes;
};

int fail(int code, const std::string& message) {
  std::fprintf(stderr, "glimpse-lab scenes: %s\n", message.c_str());
  return code;
}

// The objects of a list of folders or zoo:N items, given `role`; the zoo made with `zoo_seed`.
Expected<std::vector<EvalObject>> load_list(const std::string& list, EvalRole role, uint64_t seed, uint64_t zoo_seed,
                                            int threads) {
  std::vector<EvalObject> all;
  for (const std::string& item : split_list(list)) {
    Expected<std::vector<EvalObject>> loaded = std::vector<EvalObject>{};
    if (item.rfind("zoo:", 0) == 0) {
      const long n = std::strtol(item.c_str() + 4, nullptr, 10);
      if (n <= 0) return invalid_argument("'" + item + "': want zoo:N with N objects per category");
      loaded = zoo_objects(size_t(n), zoo_seed);
    } else {
      std::fprintf(stderr, "loading %s ...\n", item.c_str());
      loaded = load_dataset_objects(item, seed, 0, threads);
    }
    if (!loaded.ok()) return Error{loaded.error().code, item + ": " + loaded.error().message};
    for (EvalObject& o : *loaded) o.role = role, all.push_back(std::move(o));
  }
  return all;
}

// The objects the model learns (--train, --also-train) and the pool scenes are made of (--test, --test-zoo
// with another seed than the training zoo's): 0, or the exit code once the reason is printed.
int load_objects(const ScenesOptions& o, std::vector<EvalObject>& learnt, std::vector<EvalObject>& pool) {
  const uint64_t seed = o.eval.seed;
  auto train = load_list(o.train + "," + o.also_train, EvalRole::kTrainOnly, seed, seed, o.eval.threads);
  if (!train.ok()) return fail(1, train.error().message);
  learnt = std::move(*train);
  auto test = load_list(o.test, EvalRole::kTestOnly, seed, seed + 1, o.eval.threads);
  if (!test.ok()) return fail(1, test.error().message);
  pool = std::move(*test);
  if (o.test_zoo > 0) {
    auto zoo = load_list("zoo:" + std::to_string(o.test_zoo), EvalRole::kTestOnly, seed, seed + 1, o.eval.threads);
    for (EvalObject& x : *zoo) x.source = "zoo-test", pool.push_back(std::move(x));
  }
  if (learnt.empty() && !o.detect_only) return fail(2, "give --train DIR and/or --also-train zoo:N (the model's objects)");
  if (pool.empty()) return fail(2, "give --test DIR and/or --test-zoo N (the scenes' objects)");
  std::set<std::string> categories, missing;
  for (const EvalObject& x : learnt) categories.insert(x.category);
  for (const EvalObject& x : pool)
    if (!o.detect_only && !categories.count(x.category)) missing.insert(x.category);
  if (missing.empty()) return 0;
  std::string names;
  for (const std::string& c : missing) names += (names.empty() ? "" : ", ") + c;
  return fail(2, "--test: categories the model does not learn: " + names);
}

// What the report says the model learnt and the scenes hold.
void describe_sources(const ScenesOptions& o, ScenesResult& r) {
  std::string train = o.train;
  if (!o.also_train.empty()) train += (train.empty() ? "" : " with ") + o.also_train;
  r.trained_on = o.detect_only ? "nothing (detection only)"
                               : train + " (seed " + std::to_string(o.eval.seed) + ", methods " + o.eval.methods + ")";
  r.tested_on = o.test;
  if (o.test_zoo > 0)
    r.tested_on += (o.test.empty() ? "" : " and ") + std::string("the zoo, ") + std::to_string(o.test_zoo) +
                   " per category made with seed " + std::to_string(o.eval.seed + 1);
  r.tuned_on = o.tuned_on;
}

// --model FILE (a model this command saved), or the model trained on the learnt objects (kept in
// --save-model FILE when given).
Expected<Model> model_for(const ScenesOptions& o, const std::vector<EvalObject>& learnt, const EvalParams& params,
                          const EvalProgressFn& progress) {
  if (!o.model_file.empty()) {
    std::ifstream in(o.model_file, std::ios::binary);
    const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in && !in.eof()) return invalid_argument("--model: cannot read " + o.model_file);
    return deserialize(bytes);
  }
  auto model = train_lab_model(learnt, params, progress);
  if (!model.ok() || o.save_model.empty()) return model;
  const std::vector<uint8_t> bytes = serialize(*model);
  std::ofstream out(o.save_model, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  if (!out.flush()) return invalid_argument("--save-model: cannot write " + o.save_model);
  return model;
}

void print_summary(const ScenesResult& r, const std::string& out) {
  const ScenesSummary s = summarise(r);
  std::printf("scenes %zu, objects %zu (%zu at least %.0f %% visible), detections %zu\n", r.scenes.size(), s.objects,
              s.visible_objects, 100 * r.params.min_visible, s.detections);
  std::printf("recall %.1f %% (%zu / %zu), precision %.1f %% (%zu / %zu)\n", s.recall.percent(), s.recall.correct,
              s.recall.total, s.precision.percent(), s.precision.correct, s.precision.total);
  for (size_t k = 0; k < 3; ++k)
    std::printf("  recall %-14s %5.1f %% (%zu / %zu)\n", scene_kind_name(SceneKind(k)), s.recall_by_kind[k].percent(),
                s.recall_by_kind[k].correct, s.recall_by_kind[k].total);
  if (s.scene_closest.total)
    std::printf("closest: scene %.1f %%, alone %.1f %%; right and accepted: scene %.1f %%, alone %.1f %%; unknown in scenes %zu of %zu\n",
                s.scene_closest.percent(), s.alone_closest.percent(), s.scene_accepted.percent(), s.alone_accepted.percent(),
                s.scene_unknown, s.scene_closest.total);
  std::printf("segment_scene median %.1f ms\ntime %.1f s\nreport: %s\n", s.median_segment_ms, r.total_seconds,
              (std::filesystem::path(out) / "report.md").string().c_str());
}

int run(ScenesOptions& o) {
  o.eval.stages = "full";
  auto params = params_from(o.eval);
  if (!params.ok()) return fail(2, params.error().message);
  o.scenes.seed = o.eval.seed;
  o.scenes.threads = o.eval.threads;
  std::vector<EvalObject> learnt, pool;
  if (int rc = load_objects(o, learnt, pool); rc != 0) return rc;
  ProgressBar bar;
  const auto progress = [&bar](const EvalProgress& p) { bar(p); };
  std::optional<Model> model;
  const auto t0 = std::chrono::steady_clock::now();
  if (!o.detect_only) {
    auto trained = model_for(o, learnt, *params, progress);
    if (!trained.ok()) return fail(1, "the model: " + trained.error().message);
    model = std::move(*trained);
  }
  const double train_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  auto result = run_scenes(pool, model ? &*model : nullptr, o.scenes, progress);
  bar({"done", 1, 1});
  if (!result.ok()) return fail(1, result.error().message);
  describe_sources(o, *result);
  if (model && o.model_file.empty()) {
    result->timings.insert(result->timings.begin(), {"train", train_seconds, std::to_string(learnt.size()) + " objects"});
    result->total_seconds += train_seconds;
  }
  if (Status s = write_scenes_report(*result, o.out); !s.ok()) return fail(1, s.error().message);
  print_summary(*result, o.out);
  return 0;
}

// Where the objects come from and what is learnt of them.
void add_source_flags(CLI::App* cmd, ScenesOptions& o) {
  cmd->add_option("--train", o.train, "the model learns every object of these folders DIR[,DIR...]");
  cmd->add_option("--also-train", o.also_train, "more objects to learn: DIR[,DIR...] or zoo:N (the procedural zoo, N per "
                  "category, augmented beside --train as in eval); alone, the model of the zoo");
  cmd->add_option("--test", o.test,
                  "the scenes' objects: every object of these folders DIR[,DIR...], placed in metres as eval places them");
  cmd->add_option("--test-zoo", o.test_zoo, "also N zoo objects per category in the scenes, made with seed + 1 (not the training zoo's)");
  cmd->add_option("--methods", o.eval.methods, "the model's methods (eval's --methods)")->capture_default_str();
  cmd->add_option("--points", o.eval.points, "samples per training object, or 'vertices' (eval's --points)")->capture_default_str();
  cmd->add_option("--views", o.eval.views, "ideal training views per object, 1-6")->capture_default_str();
  o.eval.train_sensors = training_sensors_spec(default_training_sensors());
  cmd->add_option("--train-sensors", o.eval.train_sensors, "training-only views of simulated sensors (eval's --train-sensors)")
      ->capture_default_str();
  cmd->add_option("--model", o.model_file, "classify with this model (--save-model's) instead of training one; --train and "
                  "--also-train then only name what it learnt");
  cmd->add_option("--save-model", o.save_model, "keep the trained model in this file");
  cmd->add_flag("--detect-only", o.detect_only, "no model: segmentation and matching alone (for choosing segment_scene's parameters)");
}

// The scenes, the matching and segment_scene's parameters.
void add_scene_flags(CLI::App* cmd, ScenesOptions& o) {
  ScenesParams& s = o.scenes;
  cmd->add_option("--scenes", s.scenes, "scenes to make")->capture_default_str();
  cmd->add_option("--min-objects", s.layout.min_objects, "objects per scene, at least")->capture_default_str();
  cmd->add_option("--max-objects", s.layout.max_objects, "objects per scene, at most")->capture_default_str();
  cmd->add_option("--camera-width", s.layout.camera.width, "the depth camera's image width in pixels (57 degrees)")->capture_default_str();
  cmd->add_option("--camera-height", s.layout.camera.height, "the depth camera's image height in pixels (43 degrees)")
      ->capture_default_str();
  cmd->add_option("--min-visible", s.min_visible, "objects less visible (of what the camera sees of them alone) are not counted")
      ->capture_default_str();
  cmd->add_option("--min-iou", s.min_iou, "a detection matches a true object at this 3-D box IoU")->capture_default_str();
  SceneParams& p = s.segmentation;
  cmd->add_option("--voxel", p.voxel_m, "segment_scene: voxel_m")->capture_default_str();
  cmd->add_option("--plane-distance", p.plane_distance_m, "segment_scene: plane_distance_m")->capture_default_str();
  cmd->add_option("--min-plane-area", p.min_plane_area_m2, "segment_scene: min_plane_area_m2")->capture_default_str();
  cmd->add_option("--min-plane-fraction", p.min_plane_fraction, "segment_scene: min_plane_fraction")->capture_default_str();
  cmd->add_option("--max-planes", p.max_planes, "segment_scene: max_planes")->capture_default_str();
  cmd->add_option("--cluster-tolerance", p.cluster_tolerance_m, "segment_scene: cluster_tolerance_m")->capture_default_str();
  cmd->add_option("--reference-density", p.reference_density_per_deg2,
                  "segment_scene: reference_density_per_deg2 (0: the counts and distances as given)")
      ->capture_default_str();
  cmd->add_option("--min-object-points", p.min_object_points, "segment_scene: min_object_points")->capture_default_str();
  cmd->add_option("--max-extent", p.max_object_extent_m, "segment_scene: max_object_extent_m")->capture_default_str();
  cmd->add_option("--tuned-on", o.tuned_on, "where segment_scene's parameters were chosen, for the report")->capture_default_str();
}

}  // namespace

void add_scenes_command(CLI::App& app) {
  auto o = std::make_shared<ScenesOptions>();
  o->eval.methods = "ush,vfh,size,fusion";
  CLI::App* cmd = app.add_subcommand("scenes", "segment synthetic scenes of several objects, recognise what is found, write a report");
  add_source_flags(cmd, *o);
  add_scene_flags(cmd, *o);
  cmd->add_option("--seed", o->eval.seed, "seed of the objects' sizes, the model and the scenes")->capture_default_str();
  cmd->add_option("--threads", o->eval.threads, "threads (0: all cores); results do not depend on it")->capture_default_str();
  cmd->add_option("--out", o->out, "report folder")->capture_default_str();
  cmd->callback([o] {
    if (int rc = run(*o); rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace glimpse::lab

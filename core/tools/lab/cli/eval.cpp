// glimpse-lab eval: the paper's evaluation protocol (sec. 3.4, 4, 5) on the SHREC 2007 meshes or the
// procedural zoo, written as a report (report.md, decisions.csv, evolution SVGs). The protocol lives
// in the lab library (glimpse/lab/evaluation.h); this file declares the flags, runs the protocol and
// its ablations (ablations.cpp) and shows progress; eval_params.cpp turns the flags into EvalParams,
// eval_objects.cpp gathers the objects.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>

#include "glimpse/lab/evaluation.h"
#include "eval.h"

namespace glimpse::lab {

namespace {

// Objects tested as one of the learnt categories (the unknown ones apart).
size_t tested_known_objects(const EvalResult& r) {
  size_t n = 0;
  for (size_t i = 0; i < r.object_fold.size(); ++i) n += r.object_fold[i] >= 0 && r.object_truth[i] >= 0;
  return n;
}

// The report folder, made before the run rather than after it: 0, or the exit code once the reason is
// printed.
int make_report_folder(const std::string& out) {
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec || !std::filesystem::is_directory(out)) {
    std::fprintf(stderr, "glimpse-lab eval: --out: cannot use %s as the report folder%s%s\n", out.c_str(),
                 ec ? ": " : " (not a folder)", ec ? ec.message().c_str() : "");
    return 2;
  }
  return 0;
}

// --export-histograms' folder: 0, or the exit code once the reason is printed.
int make_export_folder(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    std::fprintf(stderr, "glimpse-lab eval: --export-histograms: cannot create %s: %s\n", dir.c_str(), ec.message().c_str());
    return 2;
  }
  return 0;
}

// The terminal's summary: accuracy per method and stage, the category changes, the open set, the time.
void print_summary(const EvalResult& result, const EvalOptions& o, const EvalParams& params, size_t objects) {
  for (const PhaseTiming& t : result.timings)
    std::fprintf(stderr, "  %-24s %7.1f s  %s\n", t.phase.c_str(), t.seconds, t.detail.c_str());
  if (result.cross_source)
    std::printf("accuracy %% (paper in brackets), trained on %s, tested on %zu objects of %s%s:\n%s", o.train.c_str(),
                tested_known_objects(result), o.test.c_str(),
                tests_learnt_objects(result) ? " (learnt too: resubstitution, not a held-out figure)" : "",
                summary_table(result).c_str());
  else
    std::printf("accuracy %% (paper in brackets), %zu objects, %d folds:\n%s", objects, params.folds,
                summary_table(result).c_str());
  std::printf("category changes (%s), finally correct / incorrect:", method_name(result.change_method));
  for (const ChangeRow& c : result.changes)
    std::printf("  <=%zu kp %.2f / %.2f", c.up_to_keypoints, c.mean_correct, c.mean_incorrect);
  if (!result.unknown_categories.empty()) {
    std::printf("\nopen set (%s): stage AUROC FAR@95%% | at the operating point: known accepted, unknown accepted, known accuracy closed -> right and accepted\n",
                method_name(result.change_method));
    for (const OpenSetRow& row : open_set_summary(result.decisions, params.stages, result.change_method,
                                                  result.unknown_categories.size()))
      std::printf("  %-6s %.3f %5.1f %% | %5.1f %% %5.1f %% %5.1f -> %5.1f %%\n", row.stage.c_str(), row.auroc, row.far_at_95,
                  row.known_acceptance, row.false_acceptance, row.known_accuracy_closed, row.known_accuracy_open);
    if (const SettleRow s = unknown_settle_summary(result.streams); s.views)
      std::printf("  streams of unknown objects: %zu of %zu settled, %zu of them as unknown\n", s.settled_views, s.views, s.correct);
  }
  std::printf("\ntime %.1f s on %d threads\n", result.total_seconds, result.threads);
  std::printf("report: %s\n", (std::filesystem::path(o.out) / "report.md").string().c_str());
}

// One run of the protocol as `o` names it, its report written to o.out: 0 with the result in `kept`
// (when given), or the exit code once the reason is printed.
int run_one(const EvalOptions& o, EvalResult* kept) {
  auto params = params_from(o);
  if (!params.ok()) {
    std::fprintf(stderr, "glimpse-lab eval: %s\n", params.error().message.c_str());
    return 2;
  }
  if (Status s = check_sources(o); !s.ok()) {
    std::fprintf(stderr, "glimpse-lab eval: %s\n", s.error().message.c_str());
    return 2;
  }
  if (int rc = make_report_folder(o.out); rc != 0) return rc;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<EvalObject> objects;
  std::string source;
  if (int rc = gather_objects(o, *params, objects, source); rc != 0) return rc;
  const double load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!o.export_histograms.empty())
    if (int rc = make_export_folder(o.export_histograms); rc != 0) return rc;
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
  print_summary(*result, o, *params, objects.size());
  if (kept) *kept = std::move(*result);
  return 0;
}

// A source's folder name in the leave-one-out report: the folder's last name (then -2, -3 ... when
// taken), or zoo:N as zoo-N.
std::string source_label(const std::string& source, const std::set<std::string>& taken) {
  std::filesystem::path p = std::filesystem::path(source).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  const std::string base = source.rfind("zoo:", 0) == 0 ? "zoo-" + source.substr(4) : p.filename().string();
  std::string label = base;
  for (int k = 2; taken.count(label); ++k) label = base + "-" + std::to_string(k);
  return label;
}

// --leave-one-out: each source tested by a model of the others, one report each in OUT/<source>, and
// OUT/leave-one-out.md over them.
int run_leave_one_out(const EvalOptions& o) {
  const std::vector<std::string> sources = split_list(o.leave_one_out);
  if (sources.size() < 2) {
    std::fprintf(stderr, "glimpse-lab eval: --leave-one-out needs at least two sources, not '%s'\n", o.leave_one_out.c_str());
    return 2;
  }
  // Every run's options, checked before the first one starts.
  std::vector<EvalOptions> folds;
  std::set<std::string> labels;
  for (size_t i = 0; i < sources.size(); ++i) {
    EvalOptions one = o;
    one.leave_one_out.clear();
    one.train.clear();
    for (size_t j = 0; j < sources.size(); ++j)
      if (j != i) one.train += (one.train.empty() ? "" : ",") + sources[j];
    one.test = sources[i];
    const std::string label = source_label(sources[i], labels);
    labels.insert(label);
    one.out = (std::filesystem::path(o.out) / label).string();
    if (Status s = check_sources(one); !s.ok()) {
      std::fprintf(stderr, "glimpse-lab eval: --leave-one-out %s (testing %s): %s\n", o.leave_one_out.c_str(),
                   sources[i].c_str(), s.error().message.c_str());
      return 2;
    }
    folds.push_back(std::move(one));
  }
  if (int rc = make_report_folder(o.out); rc != 0) return rc;
  std::vector<EvalResult> runs;
  for (size_t i = 0; i < folds.size(); ++i) {
    std::fprintf(stderr, "leave one source out: testing %s, trained on %s\n", folds[i].test.c_str(), folds[i].train.c_str());
    runs.emplace_back();
    if (int rc = run_one(folds[i], &runs.back()); rc != 0) return rc;
  }
  const std::filesystem::path path = std::filesystem::path(o.out) / "leave-one-out.md";
  std::ofstream file(path);
  file << leave_one_source_out_report(runs, runs.front().change_method);
  if (!file.flush()) {
    std::fprintf(stderr, "glimpse-lab eval: cannot write %s\n", path.string().c_str());
    return 1;
  }
  std::printf("leave one source out: %s\n", path.string().c_str());
  return 0;
}

int run_eval(const EvalOptions& o) { return o.leave_one_out.empty() ? run_one(o, nullptr) : run_leave_one_out(o); }

// ---- glimpse-lab eval's flags, in the order its help lists them ----

// Where the objects come from and which are learnt, tested or unknown.
void add_source_flags(CLI::App* cmd, EvalOptions& o) {
  auto* data = cmd->add_option("--data", o.data,
                               "dataset folders DIR[,DIR...] (DIR/<category>/<mesh>, e.g. SHREC 2007): cross-validation "
                               "over the union, by object");
  auto* train = cmd->add_option("--train", o.train, "cross-source: train on every object of these folders DIR[,DIR...]");
  auto* test = cmd->add_option("--test", o.test, "cross-source: test on every view of these folders DIR[,DIR...]");
  auto* zoo = cmd->add_option("--zoo", o.zoo, "use the procedural zoo with N objects per category instead");
  auto* loo = cmd->add_option("--leave-one-out", o.leave_one_out,
                              "leave one source out: SOURCE,SOURCE[,...] (folders or zoo:N); each is tested by a model "
                              "of the others (and --also-train), its report in OUT/<source>, and OUT/leave-one-out.md "
                              "gives every source and category, closest beside right and accepted");
  loo->excludes(data)->excludes(train)->excludes(test)->excludes(zoo);
  data->excludes(zoo)->excludes(train)->excludes(test);
  zoo->excludes(data)->excludes(train)->excludes(test);
  train->needs(test);
  test->needs(train);
  cmd->add_option("--also-train", o.also_train,
                  "extra training-only sources DIR[,DIR...] or zoo:N (the procedural zoo, N per category), learnt by "
                  "every model and never tested; the zoo beside other sources is augmented (novelty measures against a "
                  "model of the other objects)");
  cmd->add_option("--unknown", o.unknown,
                  "objects of categories no model learns DIR[,DIR...] or zoo:N, tested besides the known ones: the "
                  "report's open-set section (AUROC of novelty, false acceptance, known accuracy at the operating point) and "
                  "how their streams settle");
  cmd->add_option("--hold-out", o.hold_out,
                  "categories CAT[,CAT...] of the evaluated sources that no model learns: their objects are tested "
                  "as unknown (the open-set section from known data alone, e.g. each category in turn)");
}

// The views of every object, what each model learns from them and how it decides.
void add_training_flags(CLI::App* cmd, EvalOptions& o) {
  cmd->add_option("--train-tilt", o.tilt, "training views turned by a random tilt of up to DEG degrees (default: the recogniser's)");
  cmd->add_option("--size-blind", o.size_blind,
                  "methods of the size-blind ablation (every object 1 m tall, train and test), or 'none'")
      ->capture_default_str();
  cmd->add_option("--points", o.points,
                  "object cloud: 'vertices' (the paper) or N area-weighted samples per object (a sensor at 3x the "
                  "bounding radius sees about the same number of points whatever the object's size)")
      ->capture_default_str();
  cmd->add_option("--views", o.views, "views per object (1-6, evenly spaced of the paper's 6)")->capture_default_str();
  cmd->add_option("--train-elevations", o.train_elevations,
                  "training-only views besides the tested ones: the same azimuths from these elevations, degrees "
                  "above the horizon, comma-separated (tested views stay at the paper's 30; e.g. 0,15 for cameras "
                  "mounted low)");
  o.train_sensors = training_sensors_spec(default_training_sensors());
  cmd->add_option("--train-sensors", o.train_sensors,
                  "training-only views of simulated sensors besides the ideal ones: SENSOR:METRES:DEGREES[,...] "
                  "(depth, lidar, lidar32 or lidar64, from that distance and elevation, or ranges such as "
                  "depth:0.8-4:-10-60 from which each view draws its pose, an item listed again drawing again; the same azimuths, through the scan filters "
                  "down to the model's density, the median of its ideal training views; augmented: the decision learns them, novelty measures against a model of the other views), or 'none' (default: the recipe's, "
                  "the poses real scanners take)")
      ->capture_default_str();
  cmd->add_option("--folds", o.folds, "cross-validation folds (by object, stratified)")->capture_default_str();
  cmd->add_option("--methods", o.methods, "comma-separated: bok,bog,kgh,vfh,esf,ush,size,fusion")->capture_default_str();
  cmd->add_option("--train-on", o.train_on,
                  "full: full views only (the paper); partial: plus their top-down prefixes (--train-prefixes)")
      ->capture_default_str();
  cmd->add_option("--train-prefixes", o.train_prefixes,
                  "with --train-on partial: comma-separated fractions of each training view's points")
      ->capture_default_str();
  cmd->add_option("--decision", o.decision, "nearest-centre (the paper), centres, knn or nearest (every training vector a reference)")->capture_default_str();
  cmd->add_option("--fusion-of", o.fusion_of, "comma-separated components of fusion (default: the recogniser's)");
  cmd->add_option("--fusion-head-c", o.fusion_head_c,
                  "C of the fusion's logistic decision (its share is calibrated per model; measured with 10); 0: none, the "
                  "nearest references alone (default: the recogniser's, 10)");
  cmd->add_option("--fusion-head-rows", o.fusion_head_rows,
                  "rows of each category the fusion's logistic decision learns at most (0: every row; default: the "
                  "recogniser's, 2000)");
  cmd->add_option("--augmented-prefixes", o.augmented_prefixes,
                  "on: augmented training views (the cameras', the zoo's beside real objects) are learnt with their "
                  "top-down prefixes like the others; off: whole only (default: the recogniser's)")
      ->check(CLI::IsMember({"on", "off"}));
  cmd->add_option("--neighbours", o.neighbours, "k of the k-NN decision (0: the recogniser's default)");
  cmd->add_option("--pca-variance", o.pca_variance,
                  "explained variance the decision stage's PCA keeps (0: default; negative: no PCA, L1 on the histograms)");
  cmd->add_option("--pca-dims", o.pca_dims, "at most this many PCA dimensions in the decision stage (0: default)");
}

// The run: threads, seed, report folder, how many objects, exported histograms, poses.
void add_run_flags(CLI::App* cmd, EvalOptions& o) {
  cmd->add_option("--threads", o.threads, "threads (0: all cores); results do not depend on it")->capture_default_str();
  cmd->add_option("--seed", o.seed, "seed of sizes, samples, folds, codebooks")->capture_default_str();
  cmd->add_option("--out", o.out, "report folder")->capture_default_str();
  cmd->add_flag("--quick", o.quick, "CI size: at most 8 objects per category, 3 views, exploration every 10 keypoints");
  cmd->add_option("--max-objects", o.max_objects, "at most N objects per category (0: all)")->capture_default_str();
  cmd->add_option("--pick-objects", o.pick_objects,
                  "N objects per category of every source, drawn by --seed; a folder given as both --train and "
                  "--test then tests the objects it learnt (the paper's tables hold 18 views, 3 objects, per category)");
  cmd->add_option("--objects-per-category", o.objects_per_category,
                  "few-shot: every model learns at most K objects of each category (every learnt source together), "
                  "drawn by --seed and the fold, and tests what it would test with all of them (0: all)")
      ->capture_default_str();
  cmd->add_option("--export-histograms", o.export_histograms,
                  "folder: every fold's model writes the histograms it decides on (its training clouds and every "
                  "tested stage, one row per cloud and method) to DIR/fold<k>.csv, to try other classifiers on them");
  cmd->add_option("--poses", o.poses,
                  "dataset: categories without a natural up (sizes.csv 'any-pose', by default mechanic) seen in a "
                  "random pose per view; given: every object as its file has it (the paper)")
      ->check(CLI::IsMember({"dataset", "given"}))
      ->capture_default_str();
}

// What is tested: stages, streams, the test views' sensor and the robustness matrix.
void add_test_flags(CLI::App* cmd, EvalOptions& o) {
  cmd->add_option("--explore-step", o.explore_step, "keypoint step of the exploration grid (1: the paper's)")
      ->capture_default_str();
  cmd->add_option("--stages", o.stages, "comma-separated stages: full, Nkp (N visible keypoints), N% (of the full cloud)")
      ->capture_default_str();
  cmd->add_option("--stream-chunk", o.stream_chunk,
                  "stream every test view (--unknown objects' too) in chunks of this fraction of the full cloud (0: no "
                  "streaming)")
      ->capture_default_str();
  cmd->add_option("--sensor", o.sensor,
                  "test views from: ideal (HPR on samples, the paper's), depth (Kinect-class camera) or lidar "
                  "(16 beams; lidar32, lidar64: 32 or 64), cast against the mesh; training views stay ideal")
      ->capture_default_str();
  cmd->add_option("--distance", o.distance, "depth/lidar: metres from the sensor to the object's centre")
      ->capture_default_str();
  cmd->add_option("--elevation", o.elevation, "depth/lidar: degrees above the horizon")->capture_default_str();
  cmd->add_option("--tilt", o.scan_tilt, "test views' up off by up to DEG degrees (random direction)")
      ->capture_default_str();
  cmd->add_flag("--floor", o.floor, "depth/lidar: a floor patch under the object, removed by the ground filter");
  cmd->add_option("--outliers", o.outliers, "stray points added to each test view, x its size")->capture_default_str();
  cmd->add_option("--matrix", o.matrix, "robustness matrix: none, small (default run), full, or sensors (the depth camera from -10 to 60 "
                  "degrees at 0.8-4 m, LiDAR of 16, 32 and 64 beams at 5-20 m)")->capture_default_str();
  cmd->add_option("--matrix-views", o.matrix_views,
                  "views per tested object in the robustness matrix (0: 1 for small, 2 for full and sensors)")
      ->capture_default_str();
  cmd->add_option("--cut-margin", o.cut_margin, "keypoint stage cut below the k-th keypoint, in support radii")
      ->capture_default_str();
}

// The paper preset, keypoints and descriptors (sec. 2.2, 3.2.1-3.2.2, 4), and the keypoint ablation.
void add_keypoint_flags(CLI::App* cmd, EvalOptions& o) {
  cmd->add_option("--preset", o.preset,
                  "paper: the paper's settings for every flag not given (mesh vertices, poses as given, full-view training, "
                  "BoK/BoG/KGH/VFH, one centre per category with L1 on the histograms, r from 6 neighbours, no "
                  "rho1 cap, claims of rho1, boundary test over 2 r with a band of r/4, descriptors at rho1 up to "
                  "8 r, normalised up to 25 keypoints)");
  cmd->add_option("--support-neighbours", o.support_neighbours,
                  "support radius r = median distance to this nearest neighbour (default 30)");
  cmd->add_option("--min-neighbours", o.min_neighbours, "fewer neighbours within r: no surface (default 8)");
  cmd->add_option("--keypoint-cap", o.keypoint_cap, "keypoints need rho1 <= this x r; 0: no cap (default 8)");
  cmd->add_option("--claim-min", o.claim_min, "a keypoint claims max(rho1, this x r); 0: rho1 (default 1)");
  cmd->add_option("--boundary-band", o.boundary_band,
                  "no keypoint within this x r of a view's boundary point; 0: boundary points only (default 1)");
  cmd->add_option("--descriptor-scale", o.descriptor_scale,
                  "describe each keypoint over its rho1 clamped to [r, this x r]; 0: over r (default)");
  cmd->add_option("--boundary-radius", o.boundary_radius,
                  "the boundary test looks at neighbours within this x r (default 1)");
  cmd->add_option("--boundary-gap", o.boundary_gap, "boundary point: an angular gap wider than DEG (default 90)");
  cmd->add_option("--keypoint-response", o.keypoint_response,
                  "lambda-min (the paper: smaller principal Harris curvature) or harris (det - k tr^2, local maxima)");
  cmd->add_option("--normalise-up-to", o.normalise_up_to,
                  "keypoint histograms divided by their count up to N keypoints and by N's after (sec. 4); 0: always");
  cmd->add_option("--soft-words", o.soft_words,
                  "BoK: each keypoint shared among its N nearest words (default 1: one word, the paper)");
  cmd->add_option("--default-method", o.default_method,
                  "the method of the category changes and streams (default: the recogniser's, fusion)");
  cmd->add_flag("--keypoint-ablation", o.keypoint_ablation,
                "also re-run the keypoint methods with one keypoint or decision setting changed at a time (rho1 cap, "
                "claim radius, boundary band, r, vertices/samples, response, normalisation, PCA, decision, prefixes)");
}

}  // namespace

void add_eval_command(CLI::App& app) {
  auto o = std::make_shared<EvalOptions>();
  CLI::App* cmd = app.add_subcommand("eval", "run the paper's evaluation protocol and write a report");
  add_source_flags(cmd, *o);
  add_training_flags(cmd, *o);
  add_run_flags(cmd, *o);
  add_test_flags(cmd, *o);
  add_keypoint_flags(cmd, *o);
  cmd->callback([o, cmd] {
    if (Status s = apply_preset(*o, [cmd](const char* flag) { return cmd->get_option(flag)->count() > 0; }); !s.ok()) {
      std::fprintf(stderr, "glimpse-lab eval: %s\n", s.error().message.c_str());
      throw CLI::RuntimeError(2);
    }
    if (o->data.empty() && o->train.empty() && o->zoo == 0 && o->leave_one_out.empty()) {
      std::fprintf(stderr, "glimpse-lab eval: give --data DIR, --train DIR --test DIR, --leave-one-out DIR,DIR or --zoo N\n%s",
                   cmd->help().c_str());
      throw CLI::RuntimeError(2);
    }
    if (int rc = run_eval(*o); rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace glimpse::lab

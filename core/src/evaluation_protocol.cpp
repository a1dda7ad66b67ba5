// run_evaluation: the paper's protocol (sec. 3.4, 4) end to end. Every view's and prefix's features
// are computed once (in parallel over clouds, one thread inside each), then every fold trains from the
// stored features and classifies its test clouds; results go to preallocated slots, so they do not
// depend on the thread count.
#include <omp.h>

#include <algorithm>
#include <cctype>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <set>

#include "glimpse/evaluation.h"
#include "glimpse/geometry.h"
#include "glimpse/views.h"
#include "model_impl.h"
#include "parallel.h"

namespace glimpse {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

uint64_t mix_seed(uint64_t seed, uint64_t salt) {  // splitmix64 of the pair
  uint64_t z = seed + 0x9E3779B97F4A7C15ull * (salt + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

bool contains(const std::vector<Method>& v, Method m) { return std::find(v.begin(), v.end(), m) != v.end(); }

// The base methods whose features the evaluated methods need (fusion brings its components).
std::vector<Method> feature_methods(const TrainParams& tp) {
  std::vector<Method> base;
  auto add = [&](Method m) {
    if (m != Method::kFusion && !contains(base, m)) base.push_back(m);
  };
  for (Method m : tp.methods) add(m);
  if (contains(tp.methods, Method::kFusion))
    for (Method m : tp.fusion_of) add(m);
  return base;
}

// Which of the 6 paper viewpoints to use: n evenly spaced ones.
std::vector<size_t> viewpoint_indices(size_t n) {
  n = std::clamp<size_t>(n, 1, 6);
  std::vector<size_t> out;
  for (size_t i = 0; i < n; ++i) out.push_back(i * 6 / n);
  return out;
}

// body(i) for i in [0, n) on `threads` threads; progress is reported from thread 0 only.
template <class Body>
void parallel_for(size_t n, int threads, const std::string& phase, const EvalProgressFn& progress, Body&& body) {
  std::atomic<size_t> done{0};
  if (progress) progress({phase, 0, n});
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int64_t i = 0; i < static_cast<int64_t>(n); ++i) {
    body(static_cast<size_t>(i));
    const size_t d = ++done;
    if (progress && omp_get_thread_num() == 0) progress({phase, d, n});
  }
  if (progress) progress({phase, n, n});
}

struct View {
  int object = 0;
  int view = 0;  // index among the object's evaluated viewpoints
  Cloud cloud;
};

// The features of one top-down prefix of one view (count == view size: the full view).
struct FeatureSlot {
  size_t view = 0;
  size_t count = 0;
  bool ok = false;
  CloudFeatures features;
  std::string error;
  double seconds = 0;
};

Status validate(const std::vector<EvalObject>& objects, const EvalParams& p) {
  if (objects.empty()) return invalid_argument("no objects to evaluate");
  if (p.methods.empty()) return invalid_argument("no method to evaluate");
  if (p.folds < 2) return invalid_argument("cross-validation needs at least 2 folds");
  if (static_cast<size_t>(p.folds) > objects.size()) return invalid_argument("more folds than objects");
  if (p.stages.empty()) return invalid_argument("no stage to evaluate");
  std::set<std::string> categories;
  for (const EvalObject& o : objects) {
    if (o.mesh.vertices.empty()) return invalid_argument("object " + o.category + "/" + o.id + " has no vertices");
    categories.insert(o.category);
  }
  if (categories.size() < 2) return invalid_argument("evaluation needs at least 2 categories");
  for (const Stage& s : p.stages)
    if ((s.kind == StageKind::kKeypoints && !(s.value >= 1)) ||
        (s.kind == StageKind::kFraction && !(s.value > 0 && s.value <= 1)))
      return invalid_argument("bad stage " + stage_name(s));
  return {};
}

}  // namespace

Expected<EvalResult> run_evaluation(const std::vector<EvalObject>& objects, const EvalParams& params,
                                    std::string source, const EvalProgressFn& progress) {
  if (Status s = validate(objects, params); !s.ok()) return s.error();
  const auto t_start = Clock::now();
  EvalResult r;
  r.params = params;
  r.source = std::move(source);
  const int threads = resolve_threads(params.threads);
  r.threads = threads;
  TrainParams tp = params.train;
  tp.methods = params.methods;
  tp.seed = params.seed;
  tp.threads = threads;
  if (!contains(tp.methods, tp.default_method)) tp.default_method = tp.methods.front();
  const std::vector<Method> base = feature_methods(tp);

  // ---- objects, folds ----
  r.categories = paper_category_order(objects);
  const size_t n_objects = objects.size();
  std::vector<std::string> object_categories;
  for (const EvalObject& o : objects) {
    r.object_ids.push_back(o.category + "/" + o.id);
    r.object_truth.push_back(static_cast<int>(
        std::find(r.categories.begin(), r.categories.end(), o.category) - r.categories.begin()));
    object_categories.push_back(o.category);
  }
  r.object_fold = stratified_folds(object_categories, params.folds, params.seed);

  // ---- 1. full 3D clouds (sec. 3.4) ----
  auto t0 = Clock::now();
  std::vector<Points> full(n_objects);
  parallel_for(n_objects, threads, "object clouds", progress, [&](size_t i) {
    const Mesh& mesh = objects[i].mesh;
    if (params.points_per_object == 0) {
      full[i] = mesh_vertices(mesh).points;
    } else {
      const double area = surface_area(mesh);
      full[i] = area > 0 ? sample_surface(mesh, double(params.points_per_object) / area, mix_seed(params.seed, i)).points
                         : mesh_vertices(mesh).points;
    }
  });
  for (const Points& p : full) r.object_points.push_back(p.size());
  r.timings.push_back({"object clouds", seconds_since(t0),
                       params.points_per_object ? std::to_string(params.points_per_object) + " samples per object"
                                                : "mesh vertices"});

  // ---- 2. single views by HPR from the paper's viewpoints ----
  t0 = Clock::now();
  const std::vector<size_t> vp = viewpoint_indices(params.views_per_object);
  std::vector<View> views(n_objects * vp.size());
  parallel_for(views.size(), threads, "HPR views", progress, [&](size_t j) {
    const size_t o = j / vp.size(), v = j % vp.size();
    const std::vector<Vec3> cameras = paper_viewpoints(full[o]);
    views[j].object = static_cast<int>(o);
    views[j].view = static_cast<int>(v);
    if (vp[v] < cameras.size()) views[j].cloud = hidden_point_removal(full[o], cameras[vp[v]], params.hpr_radius_factor);
  });
  r.timings.push_back({"HPR views", seconds_since(t0), std::to_string(views.size()) + " views"});

  // ---- 3. full-view features (and the keypoint cut margin) ----
  t0 = Clock::now();
  const bool keypoint_stages =
      std::any_of(params.stages.begin(), params.stages.end(), [](const Stage& s) { return s.kind == StageKind::kKeypoints; }) ||
      params.explore_max_keypoints > 0;
  auto compute = [&](FeatureSlot& slot, const Cloud& cloud) {
    const auto c0 = Clock::now();
    auto f = cloud_features(cloud, tp, base, 1);
    slot.seconds = seconds_since(c0);
    slot.ok = f.ok();
    if (f.ok()) slot.features = std::move(*f);
    else slot.error = f.error().message;
  };
  std::vector<FeatureSlot> slots(views.size());
  std::vector<float> margin(views.size(), 0.f);
  parallel_for(views.size(), threads, "features: full views", progress, [&](size_t v) {
    slots[v].view = v;
    slots[v].count = views[v].cloud.points.size();
    compute(slots[v], views[v].cloud);
    if (keypoint_stages && views[v].cloud.points.size() > 1) {
      SurfaceParams sp = tp.features.surface;
      sp.threads = 1;
      const KdTree tree(views[v].cloud.points);
      margin[v] = params.cut_margin_supports * support_radius(tree, sp);
    }
  });
  double full_cpu = 0;
  for (const FeatureSlot& s : slots) full_cpu += s.seconds;
  r.timings.push_back({"features: full views", seconds_since(t0),
                       std::to_string(slots.size()) + " clouds, " + std::to_string(int(1000 * full_cpu / slots.size())) +
                           " ms CPU each"});

  // ---- 4. prefixes: each distinct (view, count) once ----
  t0 = Clock::now();
  r.grid = exploration_grid(params.explore_max_keypoints, params.explore_step);
  std::vector<Stage> stages = params.stages;
  for (size_t g : r.grid) {
    const Stage s{StageKind::kKeypoints, double(g)};
    if (std::find(stages.begin(), stages.end(), s) == stages.end()) stages.push_back(s);
  }
  std::vector<std::map<size_t, int>> slot_of(views.size());
  std::vector<std::vector<int>> stage_slot(views.size(), std::vector<int>(stages.size(), -1));
  std::vector<std::vector<int>> train_slots(views.size());
  auto slot_for = [&](size_t v, size_t count) -> int {
    if (count == 0) return -1;
    if (count >= views[v].cloud.points.size()) return static_cast<int>(v);
    auto [it, fresh] = slot_of[v].emplace(count, static_cast<int>(slots.size()));
    if (fresh) {
      slots.emplace_back();
      slots.back().view = v;
      slots.back().count = count;
    }
    return it->second;
  };
  for (size_t v = 0; v < views.size(); ++v) {
    const Points& pts = views[v].cloud.points;
    std::vector<float> heights;
    for (const Vec3& k : slots[v].features.positions) heights.push_back(k.z());
    for (size_t s = 0; s < stages.size(); ++s) {
      size_t count = pts.size();
      if (stages[s].kind == StageKind::kKeypoints)
        count = keypoint_prefix(pts, heights, static_cast<size_t>(stages[s].value), margin[v]);
      else if (stages[s].kind == StageKind::kFraction)
        count = fraction_prefix(pts.size(), full[views[v].object].size(), stages[s].value);
      stage_slot[v][s] = slot_for(v, count);
    }
    for (double f : tp.partial_prefixes) {
      const int id = slot_for(v, static_cast<size_t>(std::round(f * double(pts.size()))));
      if (id >= 0 && id != static_cast<int>(v)) train_slots[v].push_back(id);
    }
  }
  const size_t first_prefix = views.size();
  parallel_for(slots.size() - first_prefix, threads, "features: prefixes", progress, [&](size_t j) {
    FeatureSlot& slot = slots[first_prefix + j];
    compute(slot, reveal_top_down(views[slot.view].cloud, slot.count));
  });
  double prefix_cpu = 0;
  for (size_t i = first_prefix; i < slots.size(); ++i) prefix_cpu += slots[i].seconds;
  r.timings.push_back({"features: prefixes", seconds_since(t0),
                       std::to_string(slots.size() - first_prefix) + " distinct prefixes, " +
                           std::to_string(int(1000 * prefix_cpu / std::max<size_t>(1, slots.size() - first_prefix))) +
                           " ms CPU each"});

  // ---- stage statistics (over all views) ----
  const size_t n_cat = r.categories.size();
  for (size_t s = 0; s < stages.size(); ++s) {
    StageStats st;
    st.stage = stage_name(stages[s]);
    st.keypoints.assign(n_cat, 0), st.visible_percent.assign(n_cat, 0), st.failed.assign(n_cat, 0);
    std::vector<size_t> n(n_cat, 0);
    std::set<int> counted;
    size_t total_ok = 0;
    for (size_t v = 0; v < views.size(); ++v) {
      const int c = r.object_truth[views[v].object];
      const int id = stage_slot[v][s];
      if (id < 0 || !slots[id].ok) {
        ++st.failed[c];
        continue;
      }
      const double visible = 100.0 * double(slots[id].count) / double(std::max<size_t>(1, full[views[v].object].size()));
      st.keypoints[c] += double(slots[id].features.positions.size());
      st.visible_percent[c] += visible;
      st.mean_keypoints += double(slots[id].features.positions.size());
      st.mean_visible_percent += visible;
      ++n[c], ++total_ok;
      if (counted.insert(id).second) st.feature_seconds += slots[id].seconds;
      if (stages[s].kind == StageKind::kKeypoints && slots[v].features.positions.size() >= stages[s].value) {
        const size_t k = slots[id].features.positions.size();
        st.cut_min_keypoints = st.cut_views ? std::min(st.cut_min_keypoints, k) : k;
        st.cut_max_keypoints = std::max(st.cut_max_keypoints, k);
        st.cut_mean_keypoints += double(k);
        st.cut_visible_percent += visible;
        ++st.cut_views;
      }
    }
    if (st.cut_views) st.cut_mean_keypoints /= double(st.cut_views), st.cut_visible_percent /= double(st.cut_views);
    for (size_t c = 0; c < n_cat; ++c)
      if (n[c]) st.keypoints[c] /= double(n[c]), st.visible_percent[c] /= double(n[c]);
    if (total_ok) st.mean_keypoints /= double(total_ok), st.mean_visible_percent /= double(total_ok);
    r.stage_stats.push_back(std::move(st));
  }

  // ---- 5. cross-validation ----
  double train_seconds = 0, classify_seconds = 0;
  size_t train_samples = 0;
  std::vector<std::shared_ptr<const Model>> fold_models;
  std::vector<std::vector<int>> fold_to_ours;  // per fold: model category index -> report category index
  for (int fold = 0; fold < params.folds; ++fold) {
    const std::string tag = "fold " + std::to_string(fold + 1) + "/" + std::to_string(params.folds);
    t0 = Clock::now();
    if (progress) progress({tag + ": train", 0, 1});
    std::vector<TrainingSample> samples;
    std::vector<size_t> test_views;
    for (size_t v = 0; v < views.size(); ++v) {
      const int o = views[v].object;
      if (r.object_fold[o] == fold) {
        test_views.push_back(v);
        continue;
      }
      const std::string& cat = objects[o].category;
      if (slots[v].ok) samples.push_back({cat, objects[o].id, slots[v].features});
      for (int id : train_slots[v])
        if (slots[id].ok) samples.push_back({cat, objects[o].id, slots[id].features});
    }
    train_samples += samples.size();
    auto trained = train_on_features(std::move(samples), tp);
    if (!trained.ok()) return Error{trained.error().code, tag + ": training failed: " + trained.error().message};
    const auto model = std::make_shared<const Model>(std::move(*trained));
    fold_models.push_back(model);
    train_seconds += seconds_since(t0);
    if (progress) progress({tag + ": train", 1, 1});

    t0 = Clock::now();
    std::vector<int> to_ours;  // model category index -> report category index
    for (const std::string& c : model->categories)
      to_ours.push_back(static_cast<int>(std::find(r.categories.begin(), r.categories.end(), c) - r.categories.begin()));
    fold_to_ours.push_back(to_ours);
    const ModelImpl& impl = *model->impl;
    const size_t per_view = stages.size() * params.methods.size();
    std::vector<StageDecision> fold_decisions(test_views.size() * per_view);
    parallel_for(test_views.size() * stages.size(), threads, tag + ": classify", progress, [&](size_t item) {
      const size_t t = item / stages.size(), s = item % stages.size();
      const size_t v = test_views[t];
      const int id = stage_slot[v][s];
      const bool ok = id >= 0 && slots[id].ok;
      for (size_t m = 0; m < params.methods.size(); ++m) {
        StageDecision& d = fold_decisions[t * per_view + s * params.methods.size() + m];
        d.fold = fold;
        d.object = views[v].object;
        d.view = views[v].view;
        d.stage = stage_name(stages[s]);
        d.method = params.methods[m];
        d.truth = r.object_truth[d.object];
        d.points = id >= 0 ? slots[id].count : 0;
        d.visible_fraction = double(d.points) / double(std::max<size_t>(1, full[d.object].size()));
        if (!ok) continue;
        d.keypoints = slots[id].features.positions.size();
        const Eigen::VectorXd scores = method_scores(impl, d.method, slots[id].features);
        d.scores.assign(n_cat, 0.0);
        for (int c = 0; c < static_cast<int>(scores.size()); ++c) d.scores[to_ours[c]] = scores[c];
        d.winner = to_ours[argmax(scores)];
      }
    });
    r.decisions.insert(r.decisions.end(), std::make_move_iterator(fold_decisions.begin()),
                       std::make_move_iterator(fold_decisions.end()));
    classify_seconds += seconds_since(t0);
  }
  r.timings.push_back({"train (all folds)", train_seconds,
                       std::to_string(train_samples / params.folds) + " samples per fold"});
  r.timings.push_back({"classify (all folds)", classify_seconds,
                       std::to_string(r.decisions.size()) + " decisions"});

  // ---- 6. category changes of the best method ----
  double best = -1;
  for (Method m : params.methods) {
    double sum = 0;
    for (const Stage& s : params.stages) sum += accuracy(r.decisions, stage_name(s), m).percent();
    if (sum > best + 1e-9) best = sum, r.change_method = m;
  }
  r.traces = exploration_traces(r.decisions, r.change_method, r.grid);
  r.changes = change_summary(r.traces, params.change_up_to);

  // ---- 7. streaming: every view revealed top to bottom through a ScanSession of its fold's model ----
  if (params.stream_chunk_fraction > 0) {
    t0 = Clock::now();
    r.streams.resize(views.size());
    SessionParams sp = params.session;
    sp.method = r.change_method;
    parallel_for(views.size(), threads, "streaming sessions", progress, [&](size_t v) {
      const int o = views[v].object, fold = r.object_fold[o];
      StreamTrace& t = r.streams[v];
      t.fold = fold, t.object = o, t.view = views[v].view, t.truth = r.object_truth[o];
      auto session = ScanSession::create(fold_models[static_cast<size_t>(fold)], sp);
      if (!session.ok()) return;
      const Cloud& cloud = views[v].cloud;
      const std::vector<uint32_t> order = top_down_order(cloud.points);
      const size_t chunk = std::max<size_t>(
          1, static_cast<size_t>(std::lround(params.stream_chunk_fraction * double(full[o].size()))));
      Cloud part;
      part.sensor = cloud.sensor;
      for (size_t begin = 0; begin < order.size(); begin += chunk) {
        const size_t end = std::min(order.size(), begin + chunk);
        part.points.clear();
        for (size_t i = begin; i < end; ++i) part.points.push_back(cloud.points[order[i]]);
        auto d = (*session)->add(part);
        if (!d.ok()) break;
        t.visible_fraction.push_back(double(end) / double(std::max<size_t>(1, full[o].size())));
        t.winners.push_back(d->winner >= 0 ? fold_to_ours[static_cast<size_t>(fold)][static_cast<size_t>(d->winner)] : -1);
        t.confidence.push_back(d->confidence);
        t.settled.push_back(d->settled ? 1 : 0);
        t.keypoints.push_back(d->keypoints);
      }
    });
    size_t chunks = 0;
    for (const StreamTrace& t : r.streams) chunks += t.winners.size();
    r.timings.push_back({"streaming sessions", seconds_since(t0),
                         std::to_string(r.streams.size()) + " views, " + std::to_string(chunks) + " chunks (" +
                             method_name(r.change_method) + ")"});
  }

  // ---- 8. what looks wrong ----
  const double chance = 100.0 / double(n_cat);
  for (Method m : params.methods) {
    const Tally t = accuracy(r.decisions, "full", m);
    if (t.total && t.percent() < chance + 10)
      r.notes.push_back(std::string(method_name(m)) + " is near chance on full views (" +
                        std::to_string(int(std::lround(t.percent()))) + " %, chance " +
                        std::to_string(int(std::lround(chance))) + " %).");
  }
  for (size_t s = 0; s < params.stages.size(); ++s) {
    const Stage& stage = params.stages[s];
    const StageStats& st = r.stage_stats[s];
    size_t failed = 0;
    for (size_t f : st.failed) failed += f;
    if (failed)
      r.notes.push_back("stage " + st.stage + ": features failed on " + std::to_string(failed) + " of " +
                        std::to_string(views.size()) + " views (counted as wrong decisions).");
    if (stage.kind != StageKind::kKeypoints) continue;
    size_t short_views = 0;
    for (size_t v = 0; v < views.size(); ++v) short_views += slots[v].features.positions.size() < stage.value;
    if (short_views)
      r.notes.push_back("stage " + st.stage + ": " + std::to_string(short_views) + " of " + std::to_string(views.size()) +
                        " views have fewer than " + stage_name(stage).substr(0, stage_name(stage).size() - 2) +
                        " keypoints on the full view, so the stage is the full view for them.");
  }
  // Feature errors grouped by their message with the numbers blanked out; the first one shown in full.
  struct ErrorGroup {
    size_t clouds = 0;
    std::string example;
    std::set<std::string> objects;
  };
  std::map<std::string, ErrorGroup> errors;
  for (const FeatureSlot& slot : slots) {
    if (slot.ok) continue;
    std::string key;
    for (char c : slot.error) {
      const bool digit = std::isdigit(static_cast<unsigned char>(c));
      if (!digit) key += c;
      else if (key.empty() || key.back() != '#') key += '#';
    }
    ErrorGroup& g = errors[key];
    const std::string& object = r.object_ids[views[slot.view].object];
    if (g.clouds++ == 0)
      g.example = object + " view " + std::to_string(views[slot.view].view) + ", " + std::to_string(slot.count) +
                  " points: " + slot.error;
    g.objects.insert(object);
  }
  for (const auto& [key, g] : errors) {
    std::string list;
    for (const std::string& o : g.objects) list += (list.empty() ? "" : ", ") + o;
    r.notes.push_back("features failed on " + std::to_string(g.clouds) + " clouds (views and prefixes) of " +
                      std::to_string(g.objects.size()) + " objects (" + list + "), e.g. " + g.example);
  }
  size_t no_keypoints = 0;
  for (size_t v = 0; v < views.size(); ++v) no_keypoints += slots[v].ok && slots[v].features.positions.empty();
  if (no_keypoints)
    r.notes.push_back(std::to_string(no_keypoints) + " full views have no keypoint at all (BoK/BoG/KGH see nothing).");
  r.total_seconds = seconds_since(t_start);
  return r;
}

}  // namespace glimpse

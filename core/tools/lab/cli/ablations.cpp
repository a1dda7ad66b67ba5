// The ablations glimpse-lab eval runs beside its main evaluation: size-blind (how much is size) and the
// keypoint settings of the paper's methods. Each is the same protocol with something changed, its
// accuracies added to the main result as ablation rows of the report.
#include <algorithm>
#include <chrono>
#include <functional>

#include "eval.h"

namespace glimpse::lab {

namespace {
std::string fmt_number(double v, int decimals = 1) {
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}
}  // namespace

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
  p.export_histograms_dir.clear();  // --export-histograms holds the main run's histograms only
  p.novelty_models = false;         // the ablation's rows are its winners' accuracies: novelty is not read,
  p.train.measure_novelty = false;  // so none is calibrated (nor any cloud's top-down prefix described)
  const bool keypoints = std::any_of(p.methods.begin(), p.methods.end(), [](MethodId m) {
    return m == MethodId::kBoK || m == MethodId::kBoG || m == MethodId::kKGH;
  });
  if (!keypoints) std::erase_if(p.stages, [](const Stage& s) { return s.kind == StageKind::kKeypoints; });
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<EvalObject> known = objects;  // nor are the unknown objects'
  std::erase_if(known, [](const EvalObject& o) { return o.role == EvalRole::kUnknown; });
  auto blind = run_evaluation(common_height(std::move(known), 1.0f), p, result.source + ", every object 1 m tall",
                              [&bar](const EvalProgress& e) { bar({"size-blind: " + e.phase, e.done, e.total}); });
  if (!blind.ok()) return blind.error();
  add_ablation(result, *blind, "size-blind: every object 1 m tall, train and test");
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // Its own phases beside the count, so the report shows where the ablation's time goes.
  std::string phases;
  for (const PhaseTiming& t : blind->timings) phases += (phases.empty() ? "" : ", ") + t.phase + " " + fmt_number(t.seconds);
  result.timings.push_back({"size-blind ablation", secs,
                            std::to_string(blind->decisions.size()) + " decisions" + (phases.empty() ? "" : " (" + phases + ")")});
  result.total_seconds += secs;
  return {};
}
namespace {

struct Variant {
  std::string label;
  std::function<void(EvalParams&)> change;
};

// The keypoints' and descriptors' settings changed (sec. 2.2, 3.2.1-3.2.2): rho1's cap, the claims, the
// boundary band and test, the descriptors' scale.
void add_keypoint_variants(const TrainParams& t, std::vector<Variant>& v) {
  const KeypointParams& kp = t.features.keypoints;
  if (kp.max_radius_supports > 0 || kp.max_characteristic_radius_m > 0)
    v.push_back({"no cap on rho1", [](EvalParams& p) {
                   p.train.features.keypoints.max_radius_supports = 0;
                   p.train.features.keypoints.max_characteristic_radius_m = 0;
                 }});
  else
    v.push_back({"rho1 <= 8 r", [](EvalParams& p) { p.train.features.keypoints.max_radius_supports = 8; }});
  if (kp.claim_min_supports > 0)
    v.push_back({"claims of rho1 alone", [](EvalParams& p) { p.train.features.keypoints.claim_min_supports = 0; }});
  else
    v.push_back({"claims of max(rho1, r)", [](EvalParams& p) { p.train.features.keypoints.claim_min_supports = 1; }});
  for (float band : {0.f, 0.25f, 0.5f, 1.f})
    if (band != kp.boundary_band_supports)
      v.push_back({band > 0 ? "boundary band " + fmt_number(band, 2) + " r" : std::string("boundary points only (band 0)"),
                   [band](EvalParams& p) { p.train.features.keypoints.boundary_band_supports = band; }});
  if (kp.boundary_radius_supports != 1)
    v.push_back({"boundary test over r", [](EvalParams& p) { p.train.features.keypoints.boundary_radius_supports = 1; }});
  else
    v.push_back({"boundary test over 2 r", [](EvalParams& p) { p.train.features.keypoints.boundary_radius_supports = 2; }});
  if (t.features.descriptor.characteristic_scale_supports > 0)
    v.push_back({"descriptors over r", [](EvalParams& p) { p.train.features.descriptor.characteristic_scale_supports = 0; }});
  else
    v.push_back({"descriptors over rho1 (up to 8 r)",
                 [](EvalParams& p) { p.train.features.descriptor.characteristic_scale_supports = 8; }});
}

// The clouds' settings changed: the support radius, vertices or samples, the keypoints' response.
void add_cloud_variants(const EvalParams& params, std::vector<Variant>& v) {
  const TrainParams& t = params.train;
  const KeypointParams& kp = t.features.keypoints;
  if (t.features.surface.support_neighbours != 30)
    v.push_back({"r from the 30th neighbour", [](EvalParams& p) {
                   p.train.features.surface.support_neighbours = 30;
                   p.train.features.surface.min_neighbours = 8;
                 }});
  if (t.features.surface.support_neighbours != 8)
    v.push_back({"r from the 8th neighbour", [](EvalParams& p) {
                   p.train.features.surface.support_neighbours = 8;
                   p.train.features.surface.min_neighbours = 6;
                 }});
  if (params.points_per_object == 0) {
    v.push_back({"6000 surface samples, not vertices", [](EvalParams& p) { p.points_per_object = 6000; }});
    if (t.features.surface.support_neighbours != 30)  // random samples need more neighbours for a surface
      v.push_back({"6000 surface samples, r from the 30th neighbour", [](EvalParams& p) {
                     p.points_per_object = 6000;
                     p.train.features.surface.support_neighbours = 30;
                     p.train.features.surface.min_neighbours = 8;
                   }});
  }
  else
    v.push_back({"mesh vertices, not samples", [](EvalParams& p) { p.points_per_object = 0; }});
  if (kp.response == KeypointResponse::kLambdaMin)
    v.push_back({"Harris response (local maxima)",
                 [](EvalParams& p) { p.train.features.keypoints.response = KeypointResponse::kHarris; }});
  else
    v.push_back({"smaller Harris curvature",
                 [](EvalParams& p) { p.train.features.keypoints.response = KeypointResponse::kLambdaMin; }});
}

// The histograms' and the decision's settings changed: normalisation, soft words, PCA, the decision rule,
// training on prefixes.
void add_decision_variants(const TrainParams& t, std::vector<Variant>& v) {
  if (t.normalise_up_to_keypoints > 0 || !t.normalise_histograms)
    v.push_back({"histograms always normalised", [](EvalParams& p) {
                   p.train.normalise_up_to_keypoints = 0;
                   p.train.normalise_histograms = true;
                 }});
  if (t.normalise_up_to_keypoints > 0 || t.normalise_histograms)
    v.push_back({"raw counts", [](EvalParams& p) {
                   p.train.normalise_up_to_keypoints = 0;
                   p.train.normalise_histograms = false;
                 }});
  if (t.normalise_up_to_keypoints != 25)
    v.push_back({"normalised up to 25 keypoints", [](EvalParams& p) { p.train.normalise_up_to_keypoints = 25; }});
  if (t.bok_soft_words <= 1)
    v.push_back({"BoK soft words (3 nearest)", [](EvalParams& p) { p.train.bok_soft_words = 3; }});
  else
    v.push_back({"BoK one word per keypoint", [](EvalParams& p) { p.train.bok_soft_words = 1; }});
  if (t.decision.pca_explained_variance > 0)
    v.push_back({"L1 on the histograms (no PCA)", [](EvalParams& p) { p.train.decision.pca_explained_variance = 0; }});
  else
    v.push_back({"PCA (98 %) before L1", [](EvalParams& p) { p.train.decision.pca_explained_variance = 0.98; }});
  if (t.decision.kind != DecisionRule::kNearestReference)
    v.push_back({"nearest training vector, not centre",
                 [](EvalParams& p) { p.train.decision.kind = DecisionRule::kNearestReference; }});
  else
    v.push_back({"one centre per category", [](EvalParams& p) { p.train.decision.kind = DecisionRule::kNearestCentre; }});
  if (t.partial_prefixes.empty())
    v.push_back({"trained on top-down prefixes too",
                 [](EvalParams& p) { p.train.partial_prefixes = {0.15, 0.25, 0.35, 0.5, 0.7}; }});
  else
    v.push_back({"trained on full views only", [](EvalParams& p) { p.train.partial_prefixes.clear(); }});
}

// What the run's settings can be changed to, one at a time, in the report's order.
std::vector<Variant> keypoint_variants(const EvalParams& params) {
  std::vector<Variant> v;
  add_keypoint_variants(params.train, v);
  add_cloud_variants(params, v);
  add_decision_variants(params.train, v);
  return v;
}

}  // namespace

Status keypoint_ablation(EvalResult& result, const std::vector<EvalObject>& objects, const EvalParams& params,
                         ProgressBar& bar) {
  EvalParams base = params;
  std::erase_if(base.methods, [](MethodId m) { return m != MethodId::kBoK && m != MethodId::kBoG && m != MethodId::kKGH; });
  if (base.methods.empty()) return invalid_argument("the keypoint ablation needs bok, bog or kgh among --methods");
  if (!std::count(base.methods.begin(), base.methods.end(), base.train.default_method))
    base.train.default_method = base.methods.front();
  base.stream_chunk_fraction = 0;
  base.explore_max_keypoints = 0;
  base.matrix.clear();
  base.export_histograms_dir.clear();  // --export-histograms holds the main run's histograms only
  const auto t0 = std::chrono::steady_clock::now();
  size_t decisions = 0;
  for (const Variant& v : keypoint_variants(base)) {
    EvalParams p = base;
    v.change(p);
    auto run = run_evaluation(objects, p, result.source + ", " + v.label,
                              [&bar, &v](const EvalProgress& e) { bar({"ablation (" + v.label + "): " + e.phase, e.done, e.total}); });
    if (!run.ok()) {  // a setting that cannot train (e.g. no keypoints at all) is a finding, not an abort
      if (run.error().code == ErrorCode::kCancelled) return run.error();
      for (MethodId m : p.methods) {
        AblationRow row;
        row.group = "keypoints", row.method = m;
        row.label = v.label + " (failed: " + run.error().message + ")";
        row.accuracy.assign(result.params.stages.size(), -1.0);
        row.balanced = row.accuracy;
        result.ablations.push_back(std::move(row));
      }
      continue;
    }
    add_ablation(result, *run, v.label + " (" + keypoint_summary(*run) + ")", "keypoints");
    decisions += run->decisions.size();
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  result.timings.push_back({"keypoint ablation", secs, std::to_string(decisions) + " decisions"});
  result.total_seconds += secs;
  return {};
}

}  // namespace glimpse::lab

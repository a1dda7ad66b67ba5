// The trained part of a model's bytes (ModelImpl; serialize.cpp has the whole format): the training
// parameters, codebooks, decision stages, calibration, the fusion's logistic decision and the novelty
// model, each read back with its sizes checked against the parameters read before it.
#include <algorithm>
#include <array>
#include <map>
#include <string>

#include "glimpse/features/upright_histogram.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/model_internals.h"
#include "glimpse/learning/scores.h"
#include "glimpse/learning/train_params.h"
#include "learning/serialize_bytes.h"

namespace glimpse {

using serial::Reader;
using serial::Writer;

namespace {

void write_pca(Writer& w, const Pca& p) {
  w.vec(p.mean);
  w.mat(p.basis);
  w.vec(p.explained);
}
Pca read_pca(Reader& r, bool check = true) {
  Pca p;
  p.mean = r.vec("PCA mean");
  p.basis = r.mat("PCA basis");
  p.explained = r.vec("PCA variances");
  if (check && !r.failed() &&
      (p.basis.rows() != p.mean.size() || p.explained.size() != p.basis.cols() || p.basis.cols() == 0))
    r.fail("inconsistent PCA dimensions");
  return p;
}

void write_codebook(Writer& w, const KeypointCodebook& c) {
  w.vec(c.standardiser.mean);
  w.vec(c.standardiser.scale);
  write_pca(w, c.pca);
  w.mat(c.centres);
}
KeypointCodebook read_codebook(Reader& r, bool used, int clusters) {
  KeypointCodebook c;
  c.standardiser.mean = r.vec("standardiser mean");
  c.standardiser.scale = r.vec("standardiser scale");
  c.pca = read_pca(r, used);
  c.centres = r.mat("codebook centres");
  if (!used) return c;  // an unused codebook is written empty
  if (r.failed()) return c;
  if (c.standardiser.mean.size() != kDescriptorSize || c.standardiser.scale.size() != kDescriptorSize ||
      c.pca.mean.size() != kDescriptorSize || c.centres.rows() != clusters || c.centres.cols() != c.pca.basis.cols())
    r.fail("inconsistent keypoint codebook dimensions");
  return c;
}

void write_stage(Writer& w, const DecisionStage& s) {
  w.u8(static_cast<uint8_t>(s.kind));
  w.i32(s.categories);
  w.i32(s.neighbours);
  write_pca(w, s.pca);
  // Format 14 on: a u8, the bytes of a value (2: binary16, fit_decision's precision; 4: binary32), then
  // the values (binary32 when they are not binary16 ones, as formats 12 and 13 stored every stage).
  const bool narrow = is_binary16(s.references);
  w.u8(narrow ? 2 : 4);
  if (narrow) w.mat16(s.references);
  else w.mat32(s.references);
  w.u32(static_cast<uint32_t>(s.labels.size()));
  for (int l : s.labels) w.i32(l);
  w.f64(s.temperature);
}
DecisionStage read_stage(Reader& r, int categories, Eigen::Index histogram_size, uint32_t version) {
  DecisionStage s;
  const uint8_t kind = r.u8("decision kind");
  if (kind > static_cast<uint8_t>(DecisionRule::kNearestReference)) r.fail("unknown decision kind");
  s.kind = static_cast<DecisionRule>(kind);
  s.categories = r.i32("decision categories");
  s.neighbours = r.i32("decision neighbours");
  s.pca = read_pca(r);
  const int value_bytes = version >= 14 ? r.u8("decision reference precision") : version >= 12 ? 4 : 8;
  if (value_bytes != 2 && value_bytes != 4 && value_bytes != 8) r.fail("unknown decision reference precision");
  s.references = r.mat("decision references", r.failed() ? 8 : value_bytes);
  const uint32_t n = r.u32("decision labels");
  if (n != s.references.rows()) r.fail("decision labels do not match references");
  for (uint32_t i = 0; i < n && !r.failed(); ++i) {
    s.labels.push_back(r.i32("decision label"));
    if (s.labels.back() < 0 || s.labels.back() >= categories) r.fail("decision label out of range");
  }
  s.temperature = r.f64("decision temperature");
  if (r.failed()) return s;
  s.projected = !is_identity_projection(s.pca);
  if (s.categories != categories || s.neighbours < 1 || s.references.rows() < 1 ||
      s.references.cols() != s.pca.basis.cols() || s.pca.mean.size() != histogram_size || !(s.temperature > 0))
    r.fail("inconsistent decision stage");
  return s;
}

// Whether the model's params train method m: one of its methods, or a component of its fusion.
bool trains(const TrainParams& p, MethodId m) {
  for (MethodId q : p.methods)
    if (q == m) return true;
  if (std::find(p.methods.begin(), p.methods.end(), MethodId::kFusion) != p.methods.end())
    for (MethodId q : p.fusion_of)
      if (q == m) return true;
  return false;
}

// The training parameters, the methods and the default method. A model without the scan filters'
// parameters classifies unfiltered, as it was trained; one of format 9 or older, or without the
// "novelty_prefix" parameter, judges novelty without the cloud's prefix, as its quantiles were taken.
void read_params(Reader& r, TrainParams& p, uint32_t version) {
  const std::map<std::string, double> values = read_train_params(r, p);
  if (!values.count("filters.enabled")) p.filter_scans = false;
  if (version < 10 || !values.count("novelty_prefix")) p.novelty_prefix = 0;
  if (!(p.novelty_prefix >= 0 && p.novelty_prefix <= 1)) r.fail("novelty_prefix out of range");
  if (!(p.filters.relative_density >= 0 && p.filters.relative_density < 1e12)) r.fail("filters.relative_density out of range");
  p.methods = read_methods(r);
  p.default_method = static_cast<MethodId>(r.u8("default method"));
  p.fusion_of = read_methods(r);
  if (Status s = check_codebook_sizes(p); !s.ok()) r.fail("codebook sizes out of range: " + s.error().message);
}

// The codebooks, BoG's graph vocabulary and KGH's distance range.
void read_codebooks(Reader& r, ModelImpl& impl) {
  const TrainParams& p = impl.params;
  impl.bok = read_codebook(r, trains(p, MethodId::kBoK), p.bok_clusters);
  impl.bog = read_codebook(r, trains(p, MethodId::kBoG), p.bog_keypoint_clusters);
  impl.kgh = read_codebook(r, trains(p, MethodId::kKGH), p.kgh_clusters);
  impl.graphs.keypoint_clusters = r.i32("graph clusters");
  const uint32_t nvol = r.u32("volume centres");
  if (nvol > 1000) r.fail("too many volume centres");
  for (uint32_t i = 0; i < nvol && !r.failed(); ++i) impl.graphs.log_volume_centres.push_back(r.f64("volume centre"));
  const uint32_t ntypes = r.u32("graph types");
  r.need(size_t{ntypes} * 8, "graph types");
  for (uint32_t i = 0; i < ntypes && !r.failed(); ++i) {
    impl.graphs.types.push_back(r.u64("graph type"));
    if (i && impl.graphs.types[i] <= impl.graphs.types[i - 1]) r.fail("graph types not sorted");
  }
  if (trains(p, MethodId::kBoG) && !r.failed() &&
      (impl.graphs.keypoint_clusters != p.bog_keypoint_clusters || impl.graphs.log_volume_centres.empty()))
    r.fail("inconsistent graph vocabulary");
  impl.kgh_max_distance_m = static_cast<float>(r.f64("KGH distance"));
  if (!r.failed() && !(impl.kgh_max_distance_m > 0)) r.fail("KGH distance range must be positive");
}

// Per method, the size of its histogram (fusion: 0), as the codebooks read make it.
std::array<Eigen::Index, kMethodCount> histogram_sizes(const ModelImpl& impl) {
  const TrainParams& p = impl.params;
  return {p.bok_clusters, static_cast<Eigen::Index>(impl.graphs.types.size()),
          static_cast<Eigen::Index>(p.kgh_clusters) * p.kgh_clusters * p.kgh_distance_bins, kVfhSize, kEsfSize,
          0, kUprightHistogramSize, kVisibleSizeSize};
}

// The decision stages: a slot per method (5 in format 1), each a flag and the stage. Exactly the trained
// methods have one; fusion never does.
void read_stages(Reader& r, ModelImpl& impl, uint32_t ncat, uint32_t version) {
  const std::array<Eigen::Index, kMethodCount> sizes = histogram_sizes(impl);
  const uint32_t slots = version == 1 ? 5 : r.u8("stage slots");
  if (!r.failed() && slots > kMethodCount) r.fail("more decision stages than methods this build knows");
  for (int m = 0; m < kMethodCount && !r.failed(); ++m) {
    const MethodId method = static_cast<MethodId>(m);
    if (static_cast<uint32_t>(m) < slots && r.u8("stage flag") == 1) {
      if (method == MethodId::kFusion) r.fail("fusion has no decision stage of its own");
      else impl.stages[m] = read_stage(r, static_cast<int>(ncat), sizes[m], version);
    }
    if (!r.failed() && method != MethodId::kFusion && trains(impl.params, method) != impl.stages[m].has_value())
      r.fail(std::string("decision stage of ") + method_name(method) + " missing or unexpected");
  }
}

// The fusion's logistic decision (format 7 on), after its flag: its map, weights and biases and its
// share of the fusion's scores.
void read_fusion_head(Reader& r, ModelImpl& impl, uint32_t ncat) {
  const std::array<Eigen::Index, kMethodCount> sizes = histogram_sizes(impl);
  Chi2Logistic head;
  head.sample_steps = r.i32("fusion head steps");
  head.sample_interval = r.f64("fusion head interval");
  head.weights = r.mat("fusion head weights");
  head.bias = r.vec("fusion head bias");
  const double share = r.f64("fusion head share");
  Eigen::Index mapped = 0;
  for (MethodId m : fusion_head_methods(impl)) mapped += sizes[static_cast<int>(m)];
  mapped *= 2 * static_cast<Eigen::Index>(head.sample_steps) - 1;
  if (!r.failed() && (head.sample_steps < 1 || head.sample_steps > 16 || !(head.sample_interval > 0) ||
                      head.weights.rows() != static_cast<Eigen::Index>(ncat) || head.weights.cols() != mapped ||
                      head.bias.size() != static_cast<Eigen::Index>(ncat) || !(share >= 0 && share <= 1) ||
                      !head.weights.allFinite() || !head.bias.allFinite()))
    r.fail("inconsistent fusion logistic decision");
  impl.params.fusion_head.sample_steps = head.sample_steps;
  impl.params.fusion_head.sample_interval = head.sample_interval;
  impl.calibration.fusion_head_share = share;
  impl.fusion_head = std::move(head);
}

// The calibration folds' heads (format 13 on, the model's then its novelty model's, at the payload's
// end): a u32 count, each head's binary32 weights and binary64 biases, of the fusion head's shape.
void write_fold_heads(Writer& w, const ModelImpl& m) {
  w.u32(static_cast<uint32_t>(m.fusion_head ? m.fold_heads.size() : 0));
  if (m.fusion_head)
    for (const Chi2Logistic& fold : m.fold_heads) w.mat32(fold.weights), w.vec(fold.bias);
}

void read_fold_heads(Reader& r, ModelImpl& impl) {
  const uint32_t n = r.u32("fold head count");
  if (n > 64 || (n > 0 && !impl.fusion_head)) r.fail("fold heads without a fusion head, or too many");
  for (uint32_t k = 0; k < n && !r.failed(); ++k) {
    Chi2Logistic fold;
    fold.sample_steps = impl.fusion_head->sample_steps;
    fold.sample_interval = impl.fusion_head->sample_interval;
    fold.weights = r.mat("fold head weights", 4);
    fold.bias = r.vec("fold head bias");
    if (!r.failed() && (fold.weights.rows() != impl.fusion_head->weights.rows() ||
                        fold.weights.cols() != impl.fusion_head->weights.cols() ||
                        fold.bias.size() != impl.fusion_head->bias.size() || !fold.weights.allFinite() ||
                        !fold.bias.allFinite()))
      r.fail("inconsistent calibration fold head");
    impl.fold_heads.push_back(std::move(fold));
  }
}

// The novelty model (format 8 on), after its flag: the trained part again, of the same methods and
// calibrated method, with a calibrated novelty; none within a novelty model.
std::shared_ptr<ModelImpl> read_novelty_model(Reader& r, const ModelImpl& impl, uint32_t ncat, uint32_t version,
                                              bool nested) {
  if (nested) {
    r.fail("a novelty model within a novelty model");
    return nullptr;
  }
  std::shared_ptr<ModelImpl> novelty = read_impl(r, ncat, version, true);
  if (!r.failed() && (novelty->params.methods != impl.params.methods ||
                      novelty->calibration.method != impl.calibration.method ||
                      novelty->calibration.novelty_scale.empty()))
    r.fail("the novelty model's methods or calibration do not match the model's");
  return novelty;
}

}  // namespace

void write_methods(Writer& w, const std::vector<MethodId>& ms) {
  w.u32(static_cast<uint32_t>(ms.size()));
  for (MethodId m : ms) w.u8(static_cast<uint8_t>(m));
}
std::vector<MethodId> read_methods(Reader& r) {
  const uint32_t n = r.u32("method list");
  std::vector<MethodId> ms;
  if (n > 64) {
    r.fail("method list too long");
    return ms;
  }
  for (uint32_t i = 0; i < n; ++i) {
    const uint8_t m = r.u8("method");
    if (m >= kMethodCount) r.fail("unknown method code " + std::to_string(m));
    ms.push_back(static_cast<MethodId>(m));
  }
  return ms;
}

void write_impl(Writer& w, const ModelImpl& m, bool nested) {
  const TrainParams& p = m.params;
  write_train_params(w, p);
  write_methods(w, p.methods);
  w.u8(static_cast<uint8_t>(p.default_method));
  write_methods(w, p.fusion_of);
  write_codebook(w, m.bok);
  write_codebook(w, m.bog);
  write_codebook(w, m.kgh);
  w.i32(m.graphs.keypoint_clusters);
  w.u32(static_cast<uint32_t>(m.graphs.log_volume_centres.size()));
  for (double c : m.graphs.log_volume_centres) w.f64(c);
  w.u32(static_cast<uint32_t>(m.graphs.types.size()));
  for (uint64_t t : m.graphs.types) w.u64(t);
  w.f64(m.kgh_max_distance_m);
  w.u8(static_cast<uint8_t>(m.stages.size()));
  for (const auto& s : m.stages) {
    w.u8(s ? 1 : 0);
    if (s) write_stage(w, *s);
  }
  write_calibration(w, m.calibration);
  w.u8(m.fusion_head ? 1 : 0);
  if (m.fusion_head) {
    w.i32(m.fusion_head->sample_steps);
    w.f64(m.fusion_head->sample_interval);
    w.mat(m.fusion_head->weights);
    w.vec(m.fusion_head->bias);
    w.f64(m.calibration.fusion_head_share);
  }
  w.u8(m.novelty ? 1 : 0);
  if (m.novelty) write_impl(w, *m.novelty, true);
  if (!nested) w.u8(m.calibration.novelty_adds_evidence ? 1 : 0);
  if (!nested) w.f64(m.calibration.probability_temperature);
  if (!nested) w.f64(m.calibration.settle_probability);
  if (!nested) write_fold_heads(w, m), write_fold_heads(w, m.novelty ? *m.novelty : ModelImpl{});
}

std::shared_ptr<ModelImpl> read_impl(Reader& r, uint32_t ncat, uint32_t version, bool nested) {
  auto impl = std::make_shared<ModelImpl>();
  read_params(r, impl->params, version);
  read_codebooks(r, *impl);
  read_stages(r, *impl, ncat, version);
  if (version >= 3 && !r.failed()) read_calibration(r, impl->calibration, ncat, *impl, version);
  if (version >= 7 && !r.failed() && r.u8("fusion head flag") == 1) read_fusion_head(r, *impl, ncat);
  std::shared_ptr<ModelImpl> novelty;
  if (version >= 8 && !r.failed() && r.u8("novelty model flag") == 1)
    novelty = read_novelty_model(r, *impl, ncat, version, nested);
  // Format 8 and older take their novelty quantiles with the larger of the two evidences.
  impl->calibration.novelty_adds_evidence = false;
  if (version >= 9 && !nested && !r.failed()) {
    const uint8_t adds = r.u8("novelty combination");
    if (adds > 1) r.fail("unknown novelty combination");
    impl->calibration.novelty_adds_evidence = adds == 1;
  }
  if (version >= 11 && !nested && !r.failed()) {
    impl->calibration.probability_temperature = r.f64("probability temperature");
    impl->calibration.settle_probability = r.f64("settle probability");
    if (!(impl->calibration.probability_temperature >= 0 && impl->calibration.probability_temperature <= 100))
      r.fail("probability temperature out of range");
    if (!(impl->calibration.settle_probability >= 0 && impl->calibration.settle_probability <= 1 + 1e-6))
      r.fail("settle probability out of range");
  }
  if (version >= 13 && !nested && !r.failed()) {
    read_fold_heads(r, *impl);
    ModelImpl none;
    read_fold_heads(r, novelty ? *novelty : none);
  }
  if (novelty) {
    novelty->calibration.novelty_adds_evidence = impl->calibration.novelty_adds_evidence;
    impl->novelty = std::move(novelty);
  }
  return impl;
}

}  // namespace glimpse

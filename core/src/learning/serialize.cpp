// The model's byte format: "GLMPSMDL", u32 format version, u64 payload length, payload, u32 CRC-32 of
// the payload. All integers little-endian, reals IEEE-754 binary64 little-endian. Training parameters
// are (name, value) pairs so that later versions can add parameters and still read old models.
// deserialize() checks every length against the bytes left and every index against its table, so
// truncated, corrupt or hostile input gives an error, never undefined behaviour.
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <map>
#include <string>

#include "glimpse/learning/model.h"
#include "glimpse/learning/train_params.h"
#include "glimpse/features/upright_histogram.h"
#include "glimpse/learning/model_internals.h"
#include "glimpse/learning/scores.h"
#include "learning/serialize_bytes.h"

namespace glimpse {

namespace {

using serial::Reader;
using serial::Writer;

constexpr char kMagic[8] = {'G', 'L', 'M', 'P', 'S', 'M', 'D', 'L'};
// 1: stage slots of the first 5 methods. 2: a u8 slot count first (USH is method 6). 3: the size-only
// baseline (method 7), the calibration after the stages, the feature pipeline version and the training
// extents after the statistics. 4: the novelty calibration after the settle margin ("none of these";
// older models read with none: novelty NaN, nothing unknown but what a method cannot judge). 5: a u8
// after the novelty threshold, novelty_over_score (format 4 reads false: its quantiles are without it).
// 6: after it, a u32 count and each category's novelty object count, a u32 component count and per
// component each reference's training object (format 5 reads none: the nearest reference alone).
// 7: after the calibration, a u8 (1: the fusion's logistic decision follows: i32 feature map steps, f64
// its interval, its weights and biases, f64 its share of the fusion's scores; format 6 reads none).
// 8: after it, a u8 (1: the novelty model follows, ModelImpl::novelty: the trained part again, fitted on
// the clouds not augmented; format 7 reads none: novelty from the model's own stages).
// 9: after it (the model's, not the novelty model's), a u8: 1 novelty adds its two evidences
// (Calibration::novelty_adds_evidence, the model's and its novelty model's), 0 the larger; format 8 and
// older read 0, what their quantiles were taken with.
// 10: the same bytes; the novelty joins that of the cloud's top-down prefix (TrainParams::novelty_prefix,
// a training parameter); format 9 and older read no prefix, what their quantiles were taken with.
constexpr uint32_t kFormatVersion = 10;
constexpr uint32_t kOldestReadableVersion = 1;

uint32_t crc32(const uint8_t* data, size_t n) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) c = table[(c ^ data[i]) & 0xFF] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

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
  w.mat(s.references);
  w.u32(static_cast<uint32_t>(s.labels.size()));
  for (int l : s.labels) w.i32(l);
  w.f64(s.temperature);
}
DecisionStage read_stage(Reader& r, int categories, Eigen::Index histogram_size) {
  DecisionStage s;
  const uint8_t kind = r.u8("decision kind");
  if (kind > static_cast<uint8_t>(DecisionRule::kNearestReference)) r.fail("unknown decision kind");
  s.kind = static_cast<DecisionRule>(kind);
  s.categories = r.i32("decision categories");
  s.neighbours = r.i32("decision neighbours");
  s.pca = read_pca(r);
  s.references = r.mat("decision references");
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

// The trained part of a model; then (format 8 on) a u8, 1: the novelty model follows (ModelImpl::novelty,
// the same layout, its own flag 0); then, but for the novelty model (`nested`), how novelty combines its
// evidence (format 9 on).
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
}

// write_impl's block; `nested`: the novelty model's, which holds none itself.
std::shared_ptr<ModelImpl> read_impl(Reader& r, uint32_t ncat, uint32_t version, bool nested) {
  auto impl = std::make_shared<ModelImpl>();
  TrainParams& p = impl->params;
  const std::map<std::string, double> values = read_train_params(r, p);
  // A model from before the scan filters classifies as it did: unfiltered.
  if (!values.count("filters.enabled")) p.filter_scans = false;
  // One from before the prefix's novelty was calibrated without it.
  if (version < 10 || !values.count("novelty_prefix")) p.novelty_prefix = 0;
  if (!(p.novelty_prefix >= 0 && p.novelty_prefix <= 1)) r.fail("novelty_prefix out of range");
  if (!(p.filters.relative_density >= 0 && p.filters.relative_density < 1e12)) r.fail("filters.relative_density out of range");
  p.methods = read_methods(r);
  p.default_method = static_cast<MethodId>(r.u8("default method"));
  p.fusion_of = read_methods(r);
  if (Status s = check_codebook_sizes(p); !s.ok()) r.fail("codebook sizes out of range: " + s.error().message);
  auto used = [&](MethodId m) {
    for (MethodId q : p.methods)
      if (q == m) return true;
    if (std::find(p.methods.begin(), p.methods.end(), MethodId::kFusion) != p.methods.end())
      for (MethodId q : p.fusion_of)
        if (q == m) return true;
    return false;
  };
  impl->bok = read_codebook(r, used(MethodId::kBoK), p.bok_clusters);
  impl->bog = read_codebook(r, used(MethodId::kBoG), p.bog_keypoint_clusters);
  impl->kgh = read_codebook(r, used(MethodId::kKGH), p.kgh_clusters);
  impl->graphs.keypoint_clusters = r.i32("graph clusters");
  const uint32_t nvol = r.u32("volume centres");
  if (nvol > 1000) r.fail("too many volume centres");
  for (uint32_t i = 0; i < nvol && !r.failed(); ++i) impl->graphs.log_volume_centres.push_back(r.f64("volume centre"));
  const uint32_t ntypes = r.u32("graph types");
  r.need(size_t{ntypes} * 8, "graph types");
  for (uint32_t i = 0; i < ntypes && !r.failed(); ++i) {
    impl->graphs.types.push_back(r.u64("graph type"));
    if (i && impl->graphs.types[i] <= impl->graphs.types[i - 1]) r.fail("graph types not sorted");
  }
  if (used(MethodId::kBoG) && !r.failed() &&
      (impl->graphs.keypoint_clusters != p.bog_keypoint_clusters || impl->graphs.log_volume_centres.empty()))
    r.fail("inconsistent graph vocabulary");
  impl->kgh_max_distance_m = static_cast<float>(r.f64("KGH distance"));
  if (!r.failed() && !(impl->kgh_max_distance_m > 0)) r.fail("KGH distance range must be positive");
  const Eigen::Index sizes[kMethodCount] = {
      p.bok_clusters, static_cast<Eigen::Index>(impl->graphs.types.size()),
      static_cast<Eigen::Index>(p.kgh_clusters) * p.kgh_clusters * p.kgh_distance_bins, kVfhSize, kEsfSize,
      0, kUprightHistogramSize, kVisibleSizeSize};
  const uint32_t slots = version == 1 ? 5 : r.u8("stage slots");
  if (!r.failed() && slots > kMethodCount) r.fail("more decision stages than methods this build knows");
  for (int m = 0; m < kMethodCount && !r.failed(); ++m) {
    const MethodId method = static_cast<MethodId>(m);
    if (static_cast<uint32_t>(m) < slots && r.u8("stage flag") == 1) {
      if (method == MethodId::kFusion) r.fail("fusion has no decision stage of its own");
      else impl->stages[m] = read_stage(r, static_cast<int>(ncat), sizes[m]);
    }
    if (!r.failed() && method != MethodId::kFusion && used(method) != impl->stages[m].has_value())
      r.fail(std::string("decision stage of ") + method_name(method) + " missing or unexpected");
  }
  if (version >= 3 && !r.failed()) read_calibration(r, impl->calibration, ncat, *impl, version);
  if (version >= 7 && !r.failed() && r.u8("fusion head flag") == 1) {
    Chi2Logistic head;
    head.sample_steps = r.i32("fusion head steps");
    head.sample_interval = r.f64("fusion head interval");
    head.weights = r.mat("fusion head weights");
    head.bias = r.vec("fusion head bias");
    const double share = r.f64("fusion head share");
    Eigen::Index mapped = 0;
    for (MethodId m : fusion_head_methods(*impl)) mapped += sizes[static_cast<int>(m)];
    mapped *= 2 * static_cast<Eigen::Index>(head.sample_steps) - 1;
    if (!r.failed() && (head.sample_steps < 1 || head.sample_steps > 16 || !(head.sample_interval > 0) ||
                        head.weights.rows() != static_cast<Eigen::Index>(ncat) || head.weights.cols() != mapped ||
                        head.bias.size() != static_cast<Eigen::Index>(ncat) || !(share >= 0 && share <= 1) ||
                        !head.weights.allFinite() || !head.bias.allFinite()))
      r.fail("inconsistent fusion logistic decision");
    impl->params.fusion_head.sample_steps = head.sample_steps;
    impl->params.fusion_head.sample_interval = head.sample_interval;
    impl->calibration.fusion_head_share = share;
    impl->fusion_head = std::move(head);
  }
  std::shared_ptr<ModelImpl> novelty;
  if (version >= 8 && !r.failed() && r.u8("novelty model flag") == 1) {
    if (nested) {
      r.fail("a novelty model within a novelty model");
    } else if (novelty = read_impl(r, ncat, version, true); !r.failed()) {
      if (novelty->params.methods != impl->params.methods || novelty->calibration.method != impl->calibration.method ||
          novelty->calibration.novelty_scale.empty())
        r.fail("the novelty model's methods or calibration do not match the model's");
    }
  }
  // Format 8 and older took their novelty quantiles with the larger of the two evidences.
  impl->calibration.novelty_adds_evidence = false;
  if (version >= 9 && !nested && !r.failed()) {
    const uint8_t adds = r.u8("novelty combination");
    if (adds > 1) r.fail("unknown novelty combination");
    impl->calibration.novelty_adds_evidence = adds == 1;
  }
  if (novelty) {
    novelty->calibration.novelty_adds_evidence = impl->calibration.novelty_adds_evidence;
    impl->novelty = std::move(novelty);
  }
  return impl;
}

}  // namespace

std::vector<uint8_t> serialize(const Model& model) {
  Writer w;
  w.u32(static_cast<uint32_t>(model.categories.size()));
  for (const auto& c : model.categories) w.str(c);
  write_methods(w, model.methods);
  w.u8(static_cast<uint8_t>(model.default_method));
  w.u64(model.stats.clouds);
  w.u64(model.stats.objects);
  w.u64(model.stats.keypoints);
  w.f64(model.stats.seconds);
  w.u32(static_cast<uint32_t>(model.stats.clouds_per_category.size()));
  for (size_t n : model.stats.clouds_per_category) w.u64(n);
  w.u32(model.feature_version);
  w.f64(model.stats.min_extent_m);
  w.f64(model.stats.max_extent_m);

  w.u8(model.impl ? 1 : 0);
  if (model.impl) write_impl(w, *model.impl, false);

  Writer out;
  out.bytes.insert(out.bytes.end(), kMagic, kMagic + 8);
  out.u32(kFormatVersion);
  out.u64(w.bytes.size());
  out.bytes.insert(out.bytes.end(), w.bytes.begin(), w.bytes.end());
  out.u32(crc32(w.bytes.data(), w.bytes.size()));
  return out.bytes;
}

Expected<Model> deserialize(std::span<const uint8_t> bytes) {
  if (bytes.size() < 8 + 4 + 8 + 4 || std::memcmp(bytes.data(), kMagic, 8) != 0)
    return data_loss("not a Glimpse model (bad magic or too short: " + std::to_string(bytes.size()) + " bytes)");
  Reader head(bytes.data() + 8, bytes.size() - 8);
  const uint32_t version = head.u32("version");
  if (version < kOldestReadableVersion || version > kFormatVersion)
    return data_loss("unsupported model format version " + std::to_string(version) + " (this build reads " +
                     std::to_string(kOldestReadableVersion) + " to " + std::to_string(kFormatVersion) + ")");
  const uint64_t length = head.u64("length");
  if (length != bytes.size() - 8 - 4 - 8 - 4)
    return data_loss("model length mismatch: header says " + std::to_string(length) + " payload bytes, found " +
                     std::to_string(bytes.size() - 24));
  const uint8_t* payload = bytes.data() + 20;
  Reader tail(payload + length, 4);
  if (crc32(payload, length) != tail.u32("checksum")) return data_loss("model checksum mismatch: the bytes are corrupt");

  Reader r(payload, length);
  Model model;
  const uint32_t ncat = r.u32("category count");
  if (ncat > 100000) r.fail("too many categories");
  for (uint32_t i = 0; i < ncat && !r.failed(); ++i) model.categories.push_back(r.str("category name"));
  model.methods = read_methods(r);
  model.default_method = static_cast<MethodId>(r.u8("default method"));
  model.stats.clouds = r.u64("stats");
  model.stats.objects = r.u64("stats");
  model.stats.keypoints = r.u64("stats");
  model.stats.seconds = r.f64("stats");
  const uint32_t nper = r.u32("stats");
  if (nper != ncat) r.fail("per-category statistics do not match the categories");
  for (uint32_t i = 0; i < nper && !r.failed(); ++i) model.stats.clouds_per_category.push_back(r.u64("stats"));
  model.feature_version = 1;  // formats 1 and 2 came before the version was recorded
  if (version >= 3) {
    model.feature_version = r.u32("feature version");
    model.stats.min_extent_m = static_cast<float>(r.f64("extent"));
    model.stats.max_extent_m = static_cast<float>(r.f64("extent"));
    if (!r.failed() && !(model.stats.min_extent_m >= 0 && model.stats.max_extent_m >= model.stats.min_extent_m &&
                         model.stats.max_extent_m < 1e7f))
      r.fail("training extents out of range");
  }
  model.stats.categories = model.categories;

  const bool trained = r.u8("trained flag") == 1;
  if (trained && !r.failed()) model.impl = read_impl(r, ncat, version, false);
  if (!r.failed() && r.left() != 0) r.fail(std::to_string(r.left()) + " unexpected trailing bytes");
  if (!r.failed()) {
    if (model.methods.empty()) r.fail("the model has no method");
    for (MethodId m : model.methods)
      if (model.impl && m != MethodId::kFusion && !model.impl->stages[static_cast<int>(m)]) r.fail("a listed method has no decision stage");
    const bool fusion = std::find(model.methods.begin(), model.methods.end(), MethodId::kFusion) != model.methods.end();
    if (fusion && model.impl && component_methods(*model.impl, MethodId::kFusion).empty())
      r.fail("fusion has no component method");
    if (std::find(model.methods.begin(), model.methods.end(), model.default_method) == model.methods.end())
      r.fail("the default method is not one of the model's methods");
  }
  if (r.failed()) return data_loss("corrupt model: " + r.why());
  return model;
}

}  // namespace glimpse

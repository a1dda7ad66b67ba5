// The model's byte format: "GLMPSMDL", u32 format version, u64 payload length, payload, u32 CRC-32 of
// the payload. All integers little-endian, reals IEEE-754 binary64 little-endian. Training parameters
// are (name, value) pairs so that later versions can add parameters and still read old models.
// deserialize() checks every length against the bytes left and every index against its table, so
// truncated, corrupt or hostile input gives an error, never undefined behaviour. The header, the summary
// and the checksum are here; the trained part's blocks are serialize_impl.cpp's.
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <map>
#include <string>

#include "glimpse/learning/model.h"
#include "glimpse/learning/train_params.h"
#include "glimpse/learning/model_internals.h"
#include "glimpse/learning/scores.h"
#include "learning/serialize_bytes.h"

namespace glimpse {

namespace {

using serial::Reader;
using serial::Writer;
using serial::crc32;

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
// 11: after the novelty combination, f64 the temperature of the model's probabilities
// (Calibration::probability_temperature) and f64 its settle probability; format 10 and older read 0:
// no probabilities, streams settle on the score margin.
// 12: every decision stage's references are binary32 (the precision fit_decision keeps them at), half
// the model's bytes; format 11 and older read binary64.
// 13: at the payload's end, the calibration folds' heads (ModelImpl::fold_heads) of the model and of its
// novelty model, each a u32 count and the heads (binary32 weights, binary64 biases): where a model grown
// from it starts; format 12 and older read none.
// 14: a decision stage's references are preceded by a u8, the bytes of each value: 2 (binary16, the
// precision fit_decision keeps them at when they fit) or 4 (binary32); formats 12 and 13 read binary32.
constexpr uint32_t kFormatVersion = 14;
constexpr uint32_t kOldestReadableVersion = 1;


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
  model.feature_version = 1;  // formats 1 and 2 record no version
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

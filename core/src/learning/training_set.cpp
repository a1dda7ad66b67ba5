// A training set's bytes: "GLMPSSET", u32 format version, u32 feature pipeline version, u64 payload
// length, u64 compressed length, the payload compressed by zlib (level 1: histograms of many empty bins
// take a quarter of their bytes), u32 CRC-32 of the payload. The payload: a string table (categories and
// objects), the given clouds, then the rows with their features (binary32, as computed; a top-down
// prefix and the cloud as seen nested after the row's own). And join(), which grows a set.
#include <cstring>
#include <map>
#include <memory>
#include <string>

#include "glimpse/learning/training_set.h"

#include "learning/serialize_bytes.h"

#include <zlib.h>

namespace glimpse {

namespace {

using serial::Reader;
using serial::Writer;
using serial::crc32;

constexpr char kMagic[8] = {'G', 'L', 'M', 'P', 'S', 'S', 'E', 'T'};
constexpr uint32_t kSetFormat = 1;
constexpr int kMaxNesting = 4;  // a row, its cloud as seen, their prefixes: two levels are used

void f32(Writer& w, float v) { w.u32(std::bit_cast<uint32_t>(v)); }
float f32(Reader& r, const char* what) { return static_cast<float>(r.f32(what)); }

void write_floats(Writer& w, const float* v, size_t n) {
  w.u32(static_cast<uint32_t>(n));
  for (size_t i = 0; i < n; ++i) f32(w, v[i]);
}

// n floats of `what` into out (n read first); false when the bytes run out.
bool read_floats(Reader& r, std::vector<float>& out, const char* what) {
  const uint32_t n = r.u32(what);
  if (!r.need(size_t{n} * 4, what)) return false;
  out.resize(n);
  for (uint32_t i = 0; i < n; ++i) out[i] = f32(r, what);
  return true;
}

void write_optional(Writer& w, const std::optional<Eigen::VectorXf>& v) {
  w.u8(v ? 1 : 0);
  if (v) write_floats(w, v->data(), static_cast<size_t>(v->size()));
}

std::optional<Eigen::VectorXf> read_optional(Reader& r, const char* what) {
  if (!r.u8(what)) return std::nullopt;
  std::vector<float> v;
  if (!read_floats(r, v, what)) return std::nullopt;
  return Eigen::Map<const Eigen::VectorXf>(v.data(), static_cast<Eigen::Index>(v.size()));
}

void write_features(Writer& w, const CloudFeatures& f) {
  write_floats(w, f.positions.empty() ? nullptr : f.positions.front().data(), f.positions.size() * 3);
  write_floats(w, f.descriptors.empty() ? nullptr : f.descriptors.front().data(), f.descriptors.size() * kDescriptorSize);
  write_optional(w, f.vfh);
  write_optional(w, f.esf);
  write_optional(w, f.ush);
  write_optional(w, f.size);
  w.u64(f.points);
  f32(w, f.extent_m);
  w.u8(f.top_prefix ? 1 : 0);
  if (f.top_prefix) write_features(w, *f.top_prefix);
}

CloudFeatures read_features(Reader& r, int depth) {
  CloudFeatures f;
  std::vector<float> v;
  if (read_floats(r, v, "keypoint positions")) {
    if (v.size() % 3) r.fail("keypoint positions are not triples");
    for (size_t i = 0; i + 2 < v.size(); i += 3) f.positions.emplace_back(v[i], v[i + 1], v[i + 2]);
  }
  if (read_floats(r, v, "descriptors")) {
    if (v.size() % kDescriptorSize) r.fail("descriptors are not 12-D");
    for (size_t i = 0; i + kDescriptorSize <= v.size(); i += kDescriptorSize)
      f.descriptors.push_back(Eigen::Map<const Descriptor>(v.data() + i));
  }
  if (f.descriptors.size() != f.positions.size()) r.fail("keypoints and descriptors differ in number");
  f.vfh = read_optional(r, "vfh");
  f.esf = read_optional(r, "esf");
  f.ush = read_optional(r, "ush");
  f.size = read_optional(r, "size");
  f.points = r.u64("points");
  f.extent_m = f32(r, "extent");
  if (r.u8("prefix flag")) {
    if (depth >= kMaxNesting) {
      r.fail("features nested too deep");
      return f;
    }
    f.top_prefix = std::make_shared<const CloudFeatures>(read_features(r, depth + 1));
  }
  return f;
}

// Index of each distinct string of the set (categories and objects), in first-use order.
struct Strings {
  std::map<std::string, uint32_t> index;
  std::vector<const std::string*> order;
  uint32_t of(const std::string& s) {
    auto [it, added] = index.emplace(s, static_cast<uint32_t>(order.size()));
    if (added) order.push_back(&it->first);
    return it->second;
  }
};

std::vector<uint8_t> payload(const TrainingSet& set) {
  Strings strings;
  for (const GivenCloud& c : set.clouds) strings.of(c.category), strings.of(c.object_id);
  for (const TrainingSample& s : set.samples) strings.of(s.category), strings.of(s.object_id);
  Writer w;
  w.u32(static_cast<uint32_t>(strings.order.size()));
  for (const std::string* s : strings.order) w.str(*s);
  w.u64(set.clouds.size());
  for (const GivenCloud& c : set.clouds) {
    w.u32(strings.of(c.category));
    w.u32(strings.of(c.object_id));
    w.f64(c.relative_density);
    w.u8(c.augmented ? 1 : 0);
  }
  w.u64(set.samples.size());
  for (const TrainingSample& s : set.samples) {
    w.u32(strings.of(s.category));
    w.u32(strings.of(s.object_id));
    w.u8(static_cast<uint8_t>((s.whole ? 1 : 0) | (s.augmented ? 2 : 0) | (s.as_seen ? 4 : 0)));
    write_features(w, s.features);
    if (s.as_seen) write_features(w, *s.as_seen);
  }
  return std::move(w.bytes);
}

Expected<TrainingSet> read_payload(Reader& r, uint32_t feature_version) {
  TrainingSet set;
  set.feature_version = feature_version;
  std::vector<std::string> strings(r.u32("string count"));
  if (strings.size() > r.left() / 4) return data_loss("training set: the string table is larger than its bytes");
  for (std::string& s : strings) s = r.str("string");
  auto string_at = [&](const char* what) -> std::string {
    const uint32_t i = r.u32(what);
    if (i >= strings.size()) {
      r.fail(std::string(what) + " is not in the string table");
      return {};
    }
    return strings[i];
  };
  const uint64_t clouds = r.u64("cloud count");
  if (clouds > r.left() / 17) return data_loss("training set: more clouds than its bytes hold");
  for (uint64_t i = 0; i < clouds && !r.failed(); ++i) {
    GivenCloud c;
    c.category = string_at("category");
    c.object_id = string_at("object");
    c.relative_density = r.f64("density");
    c.augmented = r.u8("augmented") != 0;
    set.clouds.push_back(std::move(c));
  }
  const uint64_t samples = r.u64("row count");
  if (samples > r.left() / 9) return data_loss("training set: more rows than its bytes hold");
  for (uint64_t i = 0; i < samples && !r.failed(); ++i) {
    TrainingSample s;
    s.category = string_at("category");
    s.object_id = string_at("object");
    const uint8_t flags = r.u8("row flags");
    s.whole = flags & 1;
    s.augmented = flags & 2;
    s.features = read_features(r, 0);
    if (flags & 4) s.as_seen = read_features(r, 0);
    set.samples.push_back(std::move(s));
  }
  if (r.failed()) return data_loss("training set: " + r.why());
  if (r.left()) return data_loss("training set: bytes left after its last row");
  return set;
}

}  // namespace

Expected<TrainingSet> join(TrainingSet base, TrainingSet added) {
  if (base.feature_version != added.feature_version)
    return failed_precondition("the base's features are of pipeline version " + std::to_string(base.feature_version) +
                               ", the added clouds' of version " + std::to_string(added.feature_version));
  base.clouds.insert(base.clouds.end(), std::make_move_iterator(added.clouds.begin()),
                     std::make_move_iterator(added.clouds.end()));
  base.samples.insert(base.samples.end(), std::make_move_iterator(added.samples.begin()),
                      std::make_move_iterator(added.samples.end()));
  return base;
}

std::vector<uint8_t> serialize(const TrainingSet& set) {
  const std::vector<uint8_t> body = payload(set);
  uLongf packed_size = compressBound(body.size());
  std::vector<uint8_t> packed(packed_size);
  if (compress2(packed.data(), &packed_size, body.data(), body.size(), 1) != Z_OK) return {};
  packed.resize(packed_size);
  Writer w;
  w.bytes.insert(w.bytes.end(), std::begin(kMagic), std::end(kMagic));
  w.u32(kSetFormat);
  w.u32(set.feature_version);
  w.u64(body.size());
  w.u64(packed.size());
  w.bytes.insert(w.bytes.end(), packed.begin(), packed.end());
  w.u32(crc32(body.data(), body.size()));
  return std::move(w.bytes);
}

Expected<TrainingSet> deserialize_training_set(std::span<const uint8_t> bytes) {
  constexpr size_t kHead = sizeof kMagic + 24;
  if (bytes.size() < kHead + 4 || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    return invalid_argument("not a Glimpse training set (no GLMPSSET header)");
  Reader head(bytes.data() + sizeof kMagic, bytes.size() - sizeof kMagic);
  const uint32_t format = head.u32("format");
  const uint32_t feature_version = head.u32("feature version");
  const uint64_t length = head.u64("length");
  const uint64_t packed = head.u64("compressed length");
  if (format != kSetFormat)
    return invalid_argument("training set format " + std::to_string(format) + " is not " + std::to_string(kSetFormat));
  if (packed + 4 != head.left()) return data_loss("training set: its length does not match its bytes");
  if (length / 1100 > packed) return data_loss("training set: it claims more bytes than zlib packs into its own");
  std::vector<uint8_t> body(length);
  uLongf unpacked = length;
  if (uncompress(body.data(), &unpacked, bytes.data() + kHead, packed) != Z_OK || unpacked != length)
    return data_loss("training set: its compressed bytes are corrupt");
  Reader tail(bytes.data() + kHead + packed, 4);
  if (crc32(body.data(), length) != tail.u32("checksum")) return data_loss("training set checksum mismatch: the bytes are corrupt");
  Reader r(body.data(), length);
  return read_payload(r, feature_version);
}

}  // namespace glimpse

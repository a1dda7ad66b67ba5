// Model bytes of formats 3 to 13 made from a format-14 model (of no augmented cloud for 7 and older), for tests and benchmarks of models
// written before novelty existed ("none of these"; format 3 has no novelty block), before novelty was
// divided by the decision's score (format 4 lacks that byte), before it was measured over several
// training objects (format 5 lacks the reference objects that end the payload), before it joined the
// top-down prefix's (format 9) or before the model's probabilities were calibrated (format 10).
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "glimpse/features/global_descriptors.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/model_internals.h"
#include "glimpse/features/upright_histogram.h"

namespace glimpse::test {

inline uint32_t crc32(const uint8_t* data, size_t n) {
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) {
    c ^= data[i];
    for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

inline std::vector<uint8_t> with_version(std::vector<uint8_t> bytes, uint32_t version, uint64_t length) {
  std::memcpy(bytes.data() + 8, &version, 4);  // little-endian hosts, as the format
  std::memcpy(bytes.data() + 12, &length, 8);
  const uint32_t crc = crc32(bytes.data() + 20, length);
  std::memcpy(bytes.data() + 20 + length, &crc, 4);
  return bytes;
}

// The model's bytes with one training parameter's name spoilt (its last letter made '~'; unknown names
// are ignored), as written before that parameter existed: it reads with its old behaviour. Empty when
// the name is not there.
inline std::vector<uint8_t> without_parameter(std::vector<uint8_t> bytes, const std::string& name) {
  auto at = std::search(bytes.begin(), bytes.end(), name.begin(), name.end());
  if (at == bytes.end() || bytes.size() < 24) return {};
  at[static_cast<std::ptrdiff_t>(name.size()) - 1] = '~';
  uint32_t version = 0;
  std::memcpy(&version, bytes.data() + 8, 4);
  const size_t payload = bytes.size() - 24;  // read before the move below
  return with_version(std::move(bytes), version, payload);
}

// A stage's references as a block of the model's bytes: u32 rows, u32 cols, then the values of `bytes`
// bytes each (8, 4 or 2), after a u8 giving that width when `width_byte`.
inline std::vector<uint8_t> reference_block(const Eigen::MatrixXd& m, int bytes, bool width_byte) {
  std::vector<uint8_t> out;
  auto put = [&out](uint64_t v, size_t n) {
    for (size_t i = 0; i < n; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
  };
  if (width_byte) put(static_cast<uint64_t>(bytes), 1);
  put(static_cast<uint64_t>(m.rows()), 4);
  put(static_cast<uint64_t>(m.cols()), 4);
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) {
      const float v = static_cast<float>(m(r, c));
      if (bytes == 2) put(Eigen::numext::bit_cast<uint16_t>(static_cast<Eigen::half>(v)), 2);
      else if (bytes == 4) put(std::bit_cast<uint32_t>(v), 4);
      else put(std::bit_cast<uint64_t>(m(r, c)), 8);
    }
  return out;
}

// The bytes with every decision stage's reference block (the model's and its novelty model's) found by its
// values as `narrow` (reference_block) and written again as `wide`, framed as `version`. Empty when a block
// is not found.
inline std::vector<uint8_t> widen_references(std::vector<uint8_t> bytes, const Model& model, uint32_t version,
                                             int narrow, bool narrow_width_byte, int wide) {
  if (bytes.size() < 24 || !model.impl) return {};
  std::vector<const ModelImpl*> impls = {model.impl.get()};
  if (model.impl->novelty) impls.push_back(model.impl->novelty.get());
  for (const ModelImpl* impl : impls)
    for (const auto& stage : impl->stages) {
      if (!stage) continue;
      const std::vector<uint8_t> from = reference_block(stage->references, narrow, narrow_width_byte),
                                 to = reference_block(stage->references, wide, false);
      const auto at = std::search(bytes.begin() + 20, bytes.end() - 4, from.begin(), from.end());
      if (at == bytes.end() - 4) return {};
      const auto pos = at - bytes.begin();
      bytes.erase(bytes.begin() + pos, bytes.begin() + pos + static_cast<std::ptrdiff_t>(from.size()));
      bytes.insert(bytes.begin() + pos, to.begin(), to.end());
    }
  const size_t payload = bytes.size() - 24;
  return with_version(std::move(bytes), version, payload);
}

// Format 13 is format 14 with every decision stage's references as binary32, without the byte before them
// that gives their precision.
inline std::vector<uint8_t> as_format_13(std::vector<uint8_t> bytes, const Model& model) {
  return widen_references(std::move(bytes), model, 13, 2, true, 4);
}

// Format 11 is format 12 with every decision stage's references as binary64.
inline std::vector<uint8_t> as_format_11(std::vector<uint8_t> bytes, const Model& model) {
  return widen_references(std::move(bytes), model, 11, 4, false, 8);
}

// Format 12 is format 13 without the calibration folds' heads that end the payload (the model's, then its
// novelty model's: a u32 count and per head its binary32 weights and binary64 biases).
inline std::vector<uint8_t> as_format_12(std::vector<uint8_t> bytes, const Model& model) {
  if (bytes.size() < 32 || !model.impl) return {};
  auto tail = [](const ModelImpl* impl) {
    size_t n = 4;
    if (impl && impl->fusion_head)
      for (const Chi2Logistic& h : impl->fold_heads)
        n += 8 + 4 * static_cast<size_t>(h.weights.size()) + 4 + 8 * static_cast<size_t>(h.bias.size());
    return n;
  };
  const size_t cut = tail(model.impl.get()) + tail(model.impl->novelty.get());
  const size_t payload = bytes.size() - 24;
  if (cut > payload) return {};
  bytes.erase(bytes.end() - 4 - static_cast<std::ptrdiff_t>(cut), bytes.end() - 4);
  return with_version(std::move(bytes), 12, payload - cut);
}

// A format-14 model's bytes as formats 13, 12 and 11 wrote them.
inline std::vector<uint8_t> format_13_bytes(const Model& model) { return as_format_13(serialize(model), model); }
inline std::vector<uint8_t> format_12_bytes(const Model& model) { return as_format_12(format_13_bytes(model), model); }
inline std::vector<uint8_t> format_11_bytes(const Model& model) { return as_format_11(format_12_bytes(model), model); }

// Format 10 is format 11 without the probability temperature and settle probability (two f64) that end
// the payload: it reads with no probabilities.
inline std::vector<uint8_t> as_format_10(std::vector<uint8_t> bytes) {
  if (bytes.size() < 40) return {};
  const size_t payload = bytes.size() - 24;
  bytes.erase(bytes.end() - 20, bytes.end() - 4);
  return with_version(std::move(bytes), 10, payload - 16);
}

// Format 9 is format 10's bytes: it reads without the top-down prefix's novelty
// (TrainParams::novelty_prefix 0).
inline std::vector<uint8_t> as_format_9(std::vector<uint8_t> bytes) {
  bytes = as_format_10(std::move(bytes));
  if (bytes.size() < 25) return {};
  const size_t payload = bytes.size() - 24;
  return with_version(std::move(bytes), 9, payload);
}

// Format 8 is format 9 without the byte that ends the payload (serialize.cpp: 1, novelty adds its two
// evidences; format 8 reads the larger).
inline std::vector<uint8_t> as_format_8(std::vector<uint8_t> bytes) {
  bytes = as_format_9(std::move(bytes));
  if (bytes.size() < 25 || bytes[bytes.size() - 5] > 1) return {};
  const size_t payload = bytes.size() - 24;
  bytes.erase(bytes.end() - 5);
  return with_version(std::move(bytes), 8, payload - 1);
}

// Format 7 is format 8 without the novelty model's flag that ends the payload (serialize.cpp), for a
// model trained with no augmented cloud (the flag 0, nothing after it).
inline std::vector<uint8_t> as_format_7(std::vector<uint8_t> bytes) {
  bytes = as_format_8(std::move(bytes));
  if (bytes.size() < 25 || bytes[bytes.size() - 5] != 0) return {};
  const size_t payload = bytes.size() - 24;
  bytes.erase(bytes.end() - 5);
  return with_version(std::move(bytes), 7, payload - 1);
}

// Format 6 is format 7 without the fusion's logistic decision that ends the payload (serialize.cpp): its
// flag byte and, when the flag is 1, the decision of a USH + VFH fusion (the only kind tests train): i32
// steps (2), f64 interval, the weights (u32 rows = categories, u32 cols, values), the biases, the share.
inline std::vector<uint8_t> as_format_6(std::vector<uint8_t> bytes, size_t categories) {
  bytes = as_format_7(std::move(bytes));
  if (bytes.size() < 25) return {};
  const size_t payload = bytes.size() - 24;
  const size_t features = 3 * static_cast<size_t>(kUprightHistogramSize + kVfhSize);
  const size_t head = 1 + 4 + 8 + 8 + 8 * categories * features + 4 + 8 * categories + 8;
  auto u32_at = [&](size_t at) {
    uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  size_t block = 1;
  if (const size_t at = 20 + payload - head; payload > head && bytes[at] == 1 && u32_at(at + 1) == 2 &&
                                              u32_at(at + 13) == categories && u32_at(at + 17) == features)
    block = head;
  else if (bytes[20 + payload - 1] != 0)
    return {};
  bytes.erase(bytes.end() - 4 - static_cast<std::ptrdiff_t>(block), bytes.end() - 4);
  return with_version(std::move(bytes), 6, payload - block);
}

// Format 5 is format 6 without the block that ends the payload: a u32 count and the u32 novelty object
// count of each category, u32 components, per component a u32 count and the u32 object of each reference.
inline std::vector<uint8_t> as_format_5(std::vector<uint8_t> bytes, const Calibration& c) {
  bytes = as_format_6(std::move(bytes), c.novelty_objects.size());
  size_t block = 8 + 4 * c.novelty_objects.size();
  for (const auto& objects : c.reference_object) block += 4 + 4 * objects.size();
  if (bytes.size() < 24) return {};
  const size_t payload = bytes.size() - 24;
  if (payload <= block) return {};
  bytes.erase(bytes.end() - 4 - static_cast<std::ptrdiff_t>(block), bytes.end() - 4);
  return with_version(std::move(bytes), 5, payload - block);
}

// Format 4 is format 5 without the novelty_over_score byte that ends the payload.
inline std::vector<uint8_t> as_format_4(std::vector<uint8_t> bytes, const Calibration& c) {
  bytes = as_format_5(std::move(bytes), c);
  if (bytes.size() < 25) return {};
  const size_t payload = bytes.size() - 24;
  bytes.erase(bytes.end() - 5);
  return with_version(std::move(bytes), 4, payload - 1);
}

// Format 3 is format 5 without the novelty block that ends the payload: u32 components, per component a
// u32 count and its f64 scales, a u32 count and its reference flags (a byte each); u32 quantiles and
// theirs, f64 known acceptance, f64 threshold, u8 novelty over score.
inline std::vector<uint8_t> as_format_3(std::vector<uint8_t> bytes, const Calibration& c) {
  bytes = as_format_5(std::move(bytes), c);
  size_t block = 4 + 4 + 8 * c.novelty_quantiles.size() + 16 + 1;
  for (const auto& per : c.novelty_scale) block += 4 + 8 * per.size();
  for (size_t j = 0; j < c.novelty_scale.size(); ++j) block += 4 + (j < c.reference_whole.size() ? c.reference_whole[j].size() : 0);
  if (bytes.size() < 24) return {};
  const size_t payload = bytes.size() - 24;
  if (payload <= block) return {};
  bytes.erase(bytes.end() - 4 - static_cast<std::ptrdiff_t>(block), bytes.end() - 4);
  return with_version(std::move(bytes), 3, payload - block);
}

}  // namespace glimpse::test

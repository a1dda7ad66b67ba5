// The model's calibration block (format 3 on; see serialize.cpp for the whole format): the calibrated
// method, its settle margin and held-out count and accuracy; from format 4 its novelty ("none of these").
#include <cmath>
#include <string>

#include "glimpse/learning/model.h"
#include "glimpse/learning/model_internals.h"
#include "learning/serialize_bytes.h"

namespace glimpse {

using serial::Reader;
using serial::Writer;

namespace {

// Format 4: per component a u32 scale count (2 x categories + 2) and its scales, then a u32 reference count
// and a byte per reference (1: a whole cloud); the quantile table, the default known acceptance and its
// threshold (NaN when not calibrated).
void write_novelty(Writer& w, const Calibration& c) {
  w.u32(static_cast<uint32_t>(c.novelty_scale.size()));
  for (size_t j = 0; j < c.novelty_scale.size(); ++j) {
    w.u32(static_cast<uint32_t>(c.novelty_scale[j].size()));
    for (double v : c.novelty_scale[j]) w.f64(v);
    const std::vector<uint8_t> none;
    const std::vector<uint8_t>& whole = j < c.reference_whole.size() ? c.reference_whole[j] : none;
    w.u32(static_cast<uint32_t>(whole.size()));
    for (uint8_t b : whole) w.u8(b);
  }
  w.u32(static_cast<uint32_t>(c.novelty_quantiles.size()));
  for (double v : c.novelty_quantiles) w.f64(v);
  w.f64(c.known_acceptance);
  w.f64(c.novelty_threshold);
  w.u8(c.novelty_over_score ? 1 : 0);
  w.u32(static_cast<uint32_t>(c.novelty_objects.size()));
  for (int k : c.novelty_objects) w.u32(static_cast<uint32_t>(k));
  w.u32(static_cast<uint32_t>(c.reference_object.size()));
  for (const std::vector<uint32_t>& objects : c.reference_object) {
    w.u32(static_cast<uint32_t>(objects.size()));
    for (uint32_t o : objects) w.u32(o);
  }
}

// `impl`'s stages are read: each component's reference flags must match its stage.
void read_novelty(Reader& r, Calibration& c, uint32_t ncat, const ModelImpl& impl, uint32_t version) {
  const uint32_t parts = r.u32("novelty components");
  const std::vector<MethodId> components = component_methods(impl, c.method);
  if (parts != 0 && parts != components.size()) r.fail("novelty components do not match the calibrated method");
  for (uint32_t j = 0; j < parts && !r.failed(); ++j) {
    if (r.u32("novelty scales") != 2 * ncat + 2) r.fail("novelty scales do not match the categories");
    r.need(size_t{ncat} * 16 + 16, "novelty scales");
    std::vector<double> per;
    for (uint32_t k = 0; k < 2 * ncat + 2 && !r.failed(); ++k) {
      per.push_back(r.f64("novelty scale"));
      if (!(per.back() > 0 && std::isfinite(per.back()))) r.fail("novelty scale out of range");
    }
    c.novelty_scale.push_back(std::move(per));
    const uint32_t refs = r.u32("reference flags");
    const auto& stage = impl.stages[static_cast<int>(components[j])];
    if (!r.failed() && !stage) r.fail("novelty of a method without a decision stage");
    const Eigen::Index rows = r.failed() ? 0 : stage->references.rows();
    if (!r.failed() && refs != 0 && refs != static_cast<uint64_t>(rows)) r.fail("reference flags do not match the stage");
    r.need(refs, "reference flags");
    std::vector<uint8_t> whole;
    for (uint32_t k = 0; k < refs && !r.failed(); ++k) {
      whole.push_back(r.u8("reference flag"));
      if (whole.back() > 1) r.fail("reference flag out of range");
    }
    c.reference_whole.push_back(std::move(whole));
  }
  const uint32_t nq = r.u32("novelty quantiles");
  if (nq != 0 && nq != kNoveltyQuantiles) r.fail("unexpected novelty quantile count");
  r.need(size_t{nq} * 8, "novelty quantiles");
  for (uint32_t q = 0; q < nq && !r.failed(); ++q) {
    c.novelty_quantiles.push_back(r.f64("novelty quantile"));
    if (!(c.novelty_quantiles.back() >= 0 && std::isfinite(c.novelty_quantiles.back())) ||
        (q && c.novelty_quantiles[q] < c.novelty_quantiles[q - 1]))
      r.fail("novelty quantiles out of range or not ascending");
  }
  c.known_acceptance = r.f64("known acceptance");
  c.novelty_threshold = r.f64("novelty threshold");
  c.novelty_over_score = version >= 5 && r.u8("novelty over score") != 0;
  c.novelty_objects.clear();
  if (version >= 6) {
    const uint32_t counts = r.u32("novelty object counts");
    if (!r.failed() && counts != 0 && counts != ncat) r.fail("novelty object counts do not match the categories");
    r.need(size_t{counts} * 4, "novelty object counts");
    for (uint32_t k = 0; k < counts && !r.failed(); ++k) {
      c.novelty_objects.push_back(static_cast<int>(r.u32("novelty object count")));
      if (c.novelty_objects.back() < 1 || c.novelty_objects.back() > 1000000) r.fail("novelty object count out of range");
    }
    const uint32_t with_objects = r.u32("components with reference objects");
    if (!r.failed() && with_objects != 0 && with_objects != parts) r.fail("reference objects do not match the novelty components");
    for (uint32_t j = 0; j < with_objects && !r.failed(); ++j) {
      const uint32_t refs = r.u32("reference objects");
      const Eigen::Index rows = impl.stages[static_cast<int>(components[j])]->references.rows();
      if (refs != 0 && refs != static_cast<uint64_t>(rows)) r.fail("reference objects do not match the stage");
      r.need(size_t{refs} * 4, "reference objects");
      std::vector<uint32_t> objects;
      for (uint32_t k = 0; k < refs && !r.failed(); ++k) {
        objects.push_back(r.u32("reference object"));
        if (objects.back() >= refs) r.fail("reference object out of range");
      }
      c.reference_object.push_back(std::move(objects));
    }
  }
  if (r.failed()) return;
  if (c.novelty_scale.empty() != c.novelty_quantiles.empty()) r.fail("half a novelty calibration");
  else if (!(c.known_acceptance > 0 && c.known_acceptance <= 1)) r.fail("known acceptance out of range");
  else if (!c.novelty_quantiles.empty() && !(c.novelty_threshold >= 0 && std::isfinite(c.novelty_threshold)))
    r.fail("novelty threshold out of range");
}

}  // namespace

void write_calibration(Writer& w, const Calibration& c) {
  w.u8(static_cast<uint8_t>(c.method));
  w.f64(c.settle_margin);
  w.u64(c.held_out);
  w.f64(c.held_out_accuracy);
  write_novelty(w, c);
}

void read_calibration(Reader& r, Calibration& c, uint32_t ncat, const ModelImpl& impl, uint32_t version) {
  const uint8_t m = r.u8("calibration method");
  if (m >= kMethodCount) r.fail("unknown calibration method");
  c.method = static_cast<MethodId>(m);
  c.settle_margin = r.f64("settle margin");
  c.held_out = r.u64("calibration count");
  c.held_out_accuracy = r.f64("calibration accuracy");
  if (version >= 4) read_novelty(r, c, ncat, impl, version);
  if (!r.failed() && (!(c.settle_margin >= 0 && c.settle_margin <= 2) || !(c.held_out_accuracy >= 0 && c.held_out_accuracy <= 1)))
    r.fail("calibration out of range");
}

}  // namespace glimpse

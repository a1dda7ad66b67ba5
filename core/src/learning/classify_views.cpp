// A scan from several sensor positions decided view by view. Every model learns single views (one
// side of an object, as one sensor sees it), and a cloud of an object's every side is unlike any of
// them: its upright histogram and VFH hold the back as well as the front. Six depth frames around a
// clean human, fused, came out "unknown (closest: table)"; each frame alone, "human". So the scan's
// points are grouped into the views they came from, each view is classified as a single view, and
// the answers are joined.
#include <algorithm>
#include <cmath>
#include <limits>

#include "glimpse/learning/classify.h"

#include "glimpse/learning/model_internals.h"
#include "glimpse/learning/probabilities.h"

namespace glimpse {

std::vector<std::vector<uint32_t>> scan_views(const Cloud& cloud, const std::vector<std::optional<Vec3>>& point_sensors) {
  std::vector<std::vector<uint32_t>> views;
  if (point_sensors.size() != cloud.points.size() || cloud.points.empty()) return views;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  size_t finite = 0;
  for (const Vec3& p : cloud.points)
    if (p.allFinite()) sum += p.cast<double>(), ++finite;
  const Vec3 centre = finite ? Vec3((sum / double(finite)).cast<float>()) : Vec3::Zero();
  const float same = std::cos(kSameViewDeg * float(M_PI) / 180.f);
  std::vector<Vec3> looks;  // each view's first sensor direction from the centre; zero: no sensor
  size_t view = 0;
  for (size_t i = 0; i < point_sensors.size(); ++i) {
    if (i == 0 || point_sensors[i] != point_sensors[i - 1]) {  // a chunk's points share their sensor
      Vec3 look = Vec3::Zero();
      if (point_sensors[i] && (*point_sensors[i] - centre).norm() > 0) look = (*point_sensors[i] - centre).normalized();
      for (view = 0; view < looks.size(); ++view)
        if (look.isZero() ? looks[view].isZero() : !looks[view].isZero() && look.dot(looks[view]) >= same) break;
      if (view == looks.size()) looks.push_back(look), views.emplace_back();
    }
    views[view].push_back(static_cast<uint32_t>(i));
  }
  return views;
}

Expected<Classification> classify_views_apart(const Model& model, const Cloud& cloud,
                                        const std::vector<std::optional<Vec3>>& point_sensors,
                                        const std::vector<std::vector<uint32_t>>& views, MethodId method,
                                        const CancelFn& cancel) {
  std::vector<Classification> judged;
  for (const std::vector<uint32_t>& view : views) {
    Cloud one;
    std::vector<std::optional<Vec3>> sensors;
    for (uint32_t i : view) one.points.push_back(cloud.points[i]), sensors.push_back(point_sensors[i]);
    one.sensor = sensors.back();
    auto got = classify_one_view(model, one, sensors, method, cancel);
    if (cancel && cancel()) return cancelled("classification cancelled");
    if (got.ok()) judged.push_back(std::move(*got));  // a view too small or thin to decide gives no evidence
  }
  if (judged.empty()) return failed_precondition("no view of the scan can be decided alone");
  const auto by_points = [](const Classification& a, const Classification& b) { return a.points < b.points; };
  const auto can_judge = [](const Classification& c) { return !(c.unknown && !std::isfinite(c.novelty)); };
  // No view the method can judge (no keypoint in any): the largest view's answer, unknown and why.
  if (std::none_of(judged.begin(), judged.end(), can_judge))
    return std::move(*std::max_element(judged.begin(), judged.end(), by_points));
  std::erase_if(judged, [&](const Classification& c) { return !can_judge(c); });
  if (judged.size() == 1) return std::move(judged.front());
  // The method and categories, and the size judged on the largest view (its warning).
  Classification out = *std::max_element(judged.begin(), judged.end(), by_points);
  const size_t n_cat = out.scores.size();
  const bool novelty = std::all_of(judged.begin(), judged.end(),
                                   [&](const Classification& c) { return c.category_novelty.size() == n_cat; });
  out.scores.assign(n_cat, 0.0);
  out.category_novelty.assign(novelty ? n_cat : 0, 0.0);
  out.points = out.keypoints = 0;
  out.feature_ms = out.decision_ms = 0;
  out.filters = {};
  for (const Classification& c : judged) {
    for (size_t k = 0; k < n_cat; ++k) {
      out.scores[k] += c.scores[k] / double(judged.size());
      if (novelty) out.category_novelty[k] += c.category_novelty[k] / double(judged.size());
    }
    out.points += c.points, out.keypoints += c.keypoints;
    out.feature_ms += c.feature_ms, out.decision_ms += c.decision_ms;
    out.filters.input += c.filters.input, out.filters.ground += c.filters.ground;
    out.filters.outliers += c.filters.outliers, out.filters.kept += c.filters.kept;
    out.filters.voxel_m = std::max(out.filters.voxel_m, c.filters.voxel_m);
  }
  out.winner = static_cast<int>(std::max_element(out.scores.begin(), out.scores.end()) - out.scores.begin());
  out.probabilities = calibrated_probabilities(model.impl->calibration, out.method, out.scores);
  out.novelty = novelty ? out.category_novelty[static_cast<size_t>(out.winner)] : std::numeric_limits<double>::quiet_NaN();
  out.unknown = false;
  out.unknown_reason.clear();
  (void)set_known_acceptance(model, out, 0);  // unknown by the joined novelty, or by the size
  return out;
}

}  // namespace glimpse

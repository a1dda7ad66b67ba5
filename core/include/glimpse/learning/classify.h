// The steps of classify_fused (model.h) that sessions share: a scan's views decided apart, one view
// through the model's scan filters, and the decision once the filters ran.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/geometry/scan_filters.h"
#include "glimpse/learning/model.h"

namespace glimpse {

// A failed precondition naming both versions when the model's features were computed differently.
Status check_feature_version(const Model& model);

// classify_fused of one view (or of a model that does not filter): the model's filters on the whole
// cloud, then decide_after_filters.
Expected<Classification> classify_one_view(const Model& model, const Cloud& cloud,
                                       const std::vector<std::optional<Vec3>>& point_sensors, MethodId method,
                                       const CancelFn& cancel = {});

// The views of a scan from several sensor positions : its points (indices) grouped
// by the direction their sensor looks from, seen from the scan's centroid; a sensor within
// kSameViewDeg of a view's first sensor is that view's, points without a sensor are one view. One
// view: a scan from one side.
inline constexpr float kSameViewDeg = 30.f;  // half the 60 deg between the paper's neighbouring viewpoints
std::vector<std::vector<uint32_t>> scan_views(const Cloud& cloud, const std::vector<std::optional<Vec3>>& point_sensors);

// Every model learns single views, and a cloud of an object's every side is unlike any of them, so
// classify_fused decides a scan of several views view by view (classify_one_view of each) and joins the
// answers: the mean of their scores and of their per-category novelties, the winner the mean's
// argmax, the size judged on the largest view. Views a method cannot judge count only when none can.
// An error when no view can be decided alone (the caller then decides the fused scan).
Expected<Classification> classify_views_apart(const Model& model, const Cloud& cloud,
                                        const std::vector<std::optional<Vec3>>& point_sensors,
                                        const std::vector<std::vector<uint32_t>>& views, MethodId method,
                                        const CancelFn& cancel = {});

// classify_fused's decision once the model's filters ran: `filtered` is filter_scan(cloud) with `report`
// (nullptr: the model does not filter), each kept point facing the sensor of its nearest raw point.
// The session calls it with the filter it ran to see whether anything would be filtered.
Expected<Classification> decide_after_filters(const Model& model, const Cloud& cloud,
                                           const std::vector<std::optional<Vec3>>& point_sensors,
                                           const Cloud* filtered, const ScanFilterReport& report, MethodId method,
                                           std::chrono::steady_clock::time_point started, const CancelFn& cancel = {});

}  // namespace glimpse

// What glimpse scene prints, as pure functions from ClassifySceneResponse to text: the objects' table,
// one JSON object for scripts, and an SVG top view of the frame with each object's box labelled.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "glimpse/cloud.h"
#include "glimpse/v1/glimpse.pb.h"

namespace glimpse::client {

// One row per object, nearest first: # WINNER P NOVELTY POINTS RANGE_M SIZE_M (x*y*z) CENTRE (x,y,z)
// [CUT BY FRAME]; an object that could not be classified shows its status in WINNER.
std::string SceneTable(const v1::ClassifySceneResponse& r);

// {"file":..,"model":..,"version":..,"method":..,"frame_points":..,"segment_ms":..,"total_ms":..,
//  "warning":..,"planes":[{"normal":[x,y,z],"offset":..,"points":..}],"objects":[{"object":1,
//  "box_min":[..],"box_max":[..],"centroid":[..],"range_m":..,"points":.., then ClassifyJson's fields
//  or "error":{"code":..,"message":..}}]}
std::string SceneJson(std::string_view file, const v1::ClassifySceneResponse& r);

// The frame from above (x right, y up), every object's box drawn and labelled "N winner" over the
// frame's points (thinned to at most max_points, an object's in its box's colour when the response
// carries indices), and the sensor. A self-contained SVG document.
std::string SceneSvg(std::string_view title, const v1::ClassifySceneResponse& r, const Points& frame,
                     const std::optional<Vec3>& sensor, size_t max_points = 20000);

}  // namespace glimpse::client

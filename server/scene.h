// ClassifyScene's domain logic, outside the service class: the request's scene parameters checked and
// mapped onto core's SceneParams, and the scene (planes, objects, each object's classification) put
// into the response. StreamClassify's tracking streams share the parameters and the object message.
#pragma once

#include <vector>

#include "glimpse/geometry/scene.h"
#include "glimpse/learning/model.h"
#include "glimpse/session/scene_tracking.h"
#include "glimpse/v1/glimpse.pb.h"
#include "store.h"

namespace glimpse::server {

// Core's defaults where a field is unset; INVALID_ARGUMENT naming the field for a value out of range.
Expected<SceneParams> SceneParamsFromProto(const v1::SceneParameters& in);

// A tracking stream's target; INVALID_ARGUMENT when it names none (core checks its values).
Expected<TrackTarget> TrackTargetFromProto(const v1::TrackTarget& in);

// An object's box, centroid, range and point count (and its indices into the frame when asked).
void ToProto(const SceneObject& object, bool indices, v1::SceneObject* out);

// The warning for a frame whose removed planes are all steep (not +z up); empty otherwise.
std::string SceneWarning(const Scene& scene);

// Planes, objects (nearest first) and, per object, its classification or its own status.
void FillSceneResponse(const Scene& scene, const std::vector<Expected<Classification>>& results,
                       const ModelRecord& model, double model_load_ms, bool indices, v1::ClassifySceneResponse* out);

}  // namespace glimpse::server

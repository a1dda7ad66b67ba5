// ClassifyBatch's domain logic, outside the service class: the batch's limits (which apply to the
// batch as a whole), each cloud unpacked on its own (a malformed cloud fails alone), and the results
// put back in request order with a status each.
#pragma once

#include <vector>

#include "engine.h"
#include "glimpse/v1/glimpse.pb.h"
#include "limits.h"
#include "store.h"

namespace glimpse::server {

struct BatchClouds {
  std::vector<Cloud> clouds;  // the clouds that unpacked, in request order
  std::vector<int> slot;      // per request cloud: its index in `clouds`, -1 when it failed to unpack
  std::vector<Error> errors;  // per request cloud: why it failed (where slot is -1)
  size_t points = 0;          // summed over the request's clouds
};

// INVALID_ARGUMENT for a batch without clouds; RESOURCE_EXHAUSTED for more than max_batch_clouds
// clouds or more than max_points_per_cloud points in all. Otherwise every cloud is unpacked
// (CloudFromProto) and its error, if any, kept for its own result.
Expected<BatchClouds> UnpackBatch(const v1::ClassifyBatchRequest& request, const Limits& limits);

// What fails the whole call rather than one result: a cloud cancelled (the call was stopped) or a failed
// precondition (the model cannot classify at all, e.g. its feature version).
Status CheckBatchResults(const std::vector<Expected<Classification>>& results);

// One cloud's result: its status, or code 0 and the response Classify would give (model, model id and
// load time from `model`, total time the cloud's own feature and decision time).
void SetError(const Error& e, v1::ClassifyResult* r);
void SetResult(const Classification& c, const ModelRecord& model, double model_load_ms, v1::ClassifyResult* r);

// One result per request cloud: its unpacking error, its classification error, or the response
// Classify would give (model, model id and load time from `model`).
void FillBatchResponse(const BatchClouds& batch, const std::vector<Expected<Classification>>& results,
                       const ModelRecord& model, double model_load_ms, v1::ClassifyBatchResponse* out);

}  // namespace glimpse::server

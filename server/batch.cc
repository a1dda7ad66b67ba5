#include "batch.h"

#include "convert.h"
#include "proto/wire/clouds.h"
#include "proto/wire/errors.h"

namespace glimpse::server {

Expected<BatchClouds> UnpackBatch(const v1::ClassifyBatchRequest& request, const Limits& limits) {
  const size_t n = static_cast<size_t>(request.clouds_size());
  if (n == 0) return invalid_argument("the batch has no clouds");
  if (n > limits.max_batch_clouds)
    return resource_exhausted("the batch has " + std::to_string(n) + " clouds; the limit is " +
                              std::to_string(limits.max_batch_clouds) + " per call");
  BatchClouds batch;
  for (const v1::PointCloud& c : request.clouds()) batch.points += c.xyz().size() / wire::kBytesPerPoint;
  if (batch.points > limits.max_points_per_cloud)
    return resource_exhausted("the batch has " + std::to_string(batch.points) + " points in all; the limit is " +
                              std::to_string(limits.max_points_per_cloud) + " per call");
  batch.slot.assign(n, -1);
  batch.errors.resize(n);
  for (size_t i = 0; i < n; ++i) {
    auto cloud = wire::CloudFromProto(request.clouds(static_cast<int>(i)), limits.max_points_per_cloud);
    if (!cloud) {
      batch.errors[i] = Error{cloud.error().code, "cloud " + std::to_string(i) + ": " + cloud.error().message};
      continue;
    }
    batch.slot[i] = static_cast<int>(batch.clouds.size());
    batch.clouds.push_back(std::move(*cloud));
  }
  return batch;
}

Status CheckBatchResults(const std::vector<Expected<Classification>>& results) {
  for (const Expected<Classification>& r : results)
    if (!r && (r.error().code == ErrorCode::kCancelled || r.error().code == ErrorCode::kFailedPrecondition))
      return r.error();
  return {};
}

void SetError(const Error& e, v1::ClassifyResult* r) {
  const grpc::Status s = wire::ToGrpcStatus(e);
  r->set_code(static_cast<int32_t>(s.error_code()));
  r->set_message(s.error_message());
}

void SetResult(const Classification& c, const ModelRecord& model, double model_load_ms, v1::ClassifyResult* r) {
  r->set_code(0);
  v1::ClassifyResponse* resp = r->mutable_response();
  ToProto(c, resp);
  ToProto(model, resp->mutable_model());
  resp->set_model_id(static_cast<uint64_t>(model.id));
  resp->mutable_timings()->set_model_load_ms(model_load_ms);
  resp->mutable_timings()->set_total_ms(c.feature_ms + c.decision_ms);
}

void FillBatchResponse(const BatchClouds& batch, const std::vector<Expected<Classification>>& results,
                       const ModelRecord& model, double model_load_ms, v1::ClassifyBatchResponse* out) {
  for (size_t i = 0; i < batch.slot.size(); ++i) {
    v1::ClassifyResult* r = out->add_results();
    const int slot = batch.slot[i];
    if (slot < 0) {
      SetError(batch.errors[i], r);
      continue;
    }
    const Expected<Classification>& c = results[static_cast<size_t>(slot)];
    if (!c) {
      SetError(Error{c.error().code, "cloud " + std::to_string(i) + ": " + c.error().message}, r);
      continue;
    }
    SetResult(*c, model, model_load_ms, r);
  }
}

}  // namespace glimpse::server

#include "client/batch_client.h"

#include "proto/wire/clouds.h"

namespace glimpse::client {

std::vector<std::pair<size_t, size_t>> BatchRanges(std::span<const size_t> sizes, const BatchLimits& limits) {
  std::vector<std::pair<size_t, size_t>> out;
  size_t begin = 0, points = 0;
  for (size_t i = 0; i < sizes.size(); ++i) {
    if (i > begin && (i - begin >= limits.clouds || points + sizes[i] > limits.points)) {
      out.emplace_back(begin, i);
      begin = i;
      points = 0;
    }
    points += sizes[i];
  }
  if (begin < sizes.size()) out.emplace_back(begin, sizes.size());
  return out;
}

BatchClassifier::BatchClassifier(const ConnectionOptions& conn, v1::Glimpse::Stub& stub, v1::ModelRef model,
                                 v1::Method method, double timeout_per_cloud_s, BatchLimits limits)
    : conn_(conn), stub_(stub), model_(std::move(model)), method_(method),
      timeout_per_cloud_s_(timeout_per_cloud_s), limits_(limits) {}

BatchAnswers BatchClassifier::Classify(std::span<const Cloud> clouds) {
  BatchAnswers result;
  result.answers.resize(clouds.size());
  std::vector<size_t> sizes;
  for (const Cloud& c : clouds) sizes.push_back(c.points.size());
  for (const auto& [begin, end] : BatchRanges(sizes, limits_)) {
    const std::span<CloudAnswer> out(result.answers.data() + begin, end - begin);
    grpc::Status s = end - begin > 1 && batch_supported_ ? Batch(clouds.subspan(begin, end - begin), out)
                                                          : grpc::Status::OK;
    // An older server (UNIMPLEMENTED), or one whose limits are below ours (RESOURCE_EXHAUSTED: the
    // batch's clouds or points in all): one call per cloud from here on, each refused alone if too big.
    if (s.error_code() == grpc::StatusCode::UNIMPLEMENTED || s.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED)
      batch_supported_ = false;
    if (end - begin == 1 || !batch_supported_)
      for (size_t i = begin; i < end; ++i) {
        const grpc::Status one = Single(clouds[i], result.answers[i]);
        if (!one.ok() && result.call.ok() && one.error_code() != grpc::StatusCode::INVALID_ARGUMENT) result.call = one;
      }
    else if (!s.ok() && result.call.ok()) result.call = s;
  }
  return result;
}

grpc::Status BatchClassifier::Batch(std::span<const Cloud> clouds, std::span<CloudAnswer> out) {
  v1::ClassifyBatchRequest request;
  *request.mutable_model() = model_;
  request.set_method(method_);
  request.set_known_acceptance(known_acceptance_);
  for (const Cloud& c : clouds) wire::CloudToProto(c, request.add_clouds());
  grpc::ClientContext context;
  PrepareContext(context, conn_, timeout_per_cloud_s_ * double(clouds.size()));
  v1::ClassifyBatchResponse response;
  const grpc::Status s = stub_.ClassifyBatch(&context, request, &response);
  if (s.error_code() == grpc::StatusCode::UNIMPLEMENTED) return s;
  for (size_t i = 0; i < out.size(); ++i) {
    CloudAnswer& a = out[i];
    if (!s.ok()) {
      a.code = s.error_code();
      a.message = s.error_message();
    } else if (i >= size_t(response.results_size())) {
      a.code = grpc::StatusCode::INTERNAL;
      a.message = "the server answered " + std::to_string(response.results_size()) + " of " +
                  std::to_string(out.size()) + " clouds";
    } else if (const v1::ClassifyResult& r = response.results(int(i)); r.code() != 0) {
      a.code = static_cast<grpc::StatusCode>(r.code());
      a.message = r.message();
    } else {
      a.response = r.response();
    }
  }
  return s;
}

grpc::Status BatchClassifier::Single(const Cloud& cloud, CloudAnswer& out) {
  out = CloudAnswer{};  // a refused batch's status is not this call's
  v1::ClassifyRequest request;
  *request.mutable_model() = model_;
  request.set_method(method_);
  request.set_known_acceptance(known_acceptance_);
  wire::CloudToProto(cloud, request.mutable_cloud());
  grpc::ClientContext context;
  PrepareContext(context, conn_, timeout_per_cloud_s_);
  v1::ClassifyResponse response;
  const grpc::Status s = stub_.Classify(&context, request, &response);
  if (s.ok()) {
    out.response = std::move(response);
  } else {
    out.code = s.error_code();
    out.message = s.error_message();
  }
  return s;
}

}  // namespace glimpse::client

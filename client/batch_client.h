// Classifying many clouds with one model: ClassifyBatch calls within the server's default limits
// (clouds and points per call), one Classify per cloud for a single cloud or for a server that has no
// ClassifyBatch (UNIMPLEMENTED). Used by `glimpse classify` and `glimpse evaluate`.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "client/connection.h"
#include "glimpse/cloud.h"

namespace glimpse::client {

// One cloud's answer: the response, or the status that stopped it.
struct CloudAnswer {
  std::optional<v1::ClassifyResponse> response;
  grpc::StatusCode code = grpc::StatusCode::OK;
  std::string message;
};

struct BatchAnswers {
  grpc::Status call;                // the first call that failed as a whole (its status is every answer's too)
  std::vector<CloudAnswer> answers; // one per cloud, in order
};

struct BatchLimits {
  size_t clouds = 64;          // per call (the server's default limit is 256)
  size_t points = 1'000'000;   // per call: the server's default points limit
};

// Consecutive groups of `sizes` (points per cloud) within the limits; a cloud alone above the points
// limit is a group of its own (the server will say what is wrong with it).
std::vector<std::pair<size_t, size_t>> BatchRanges(std::span<const size_t> sizes, const BatchLimits& limits);

class BatchClassifier {
 public:
  // timeout_per_cloud_s: each call's deadline is this times its clouds (unless conn sets one).
  BatchClassifier(const ConnectionOptions& conn, v1::Glimpse::Stub& stub, v1::ModelRef model, v1::Method method,
                  double timeout_per_cloud_s, BatchLimits limits = {});
  BatchAnswers Classify(std::span<const Cloud> clouds);
  // The operating point of "unknown" sent with every call (0: the model's default).
  void set_known_acceptance(double known_acceptance) { known_acceptance_ = known_acceptance; }

 private:
  grpc::Status Batch(std::span<const Cloud> clouds, std::span<CloudAnswer> out);
  grpc::Status Single(const Cloud& cloud, CloudAnswer& out);

  const ConnectionOptions& conn_;
  v1::Glimpse::Stub& stub_;
  v1::ModelRef model_;
  v1::Method method_;
  double timeout_per_cloud_s_;
  BatchLimits limits_;
  bool batch_supported_ = true;
  double known_acceptance_ = 0;
};

}  // namespace glimpse::client

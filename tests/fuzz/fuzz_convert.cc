// libFuzzer target: request -> core conversion of the service (proto/wire, server/train.h).
// The first byte picks the message (ClassifyRequest, ScanChunk, TrainRequest after a header, or a
// TrainHeader); the rest is its protobuf encoding. Checks: no crash; an accepted cloud has only
// finite points and packs back to exactly the bytes it came from.
#include <cstddef>
#include <cstdint>

#include "glimpse/learning/train_params.h"
#include "proto/wire/clouds.h"
#include "proto/wire/methods.h"
#include "proto/wire/model_names.h"
#include "proto/wire/train_params.h"
#include "server/train.h"

namespace {

void CheckCloud(const glimpse::Expected<glimpse::Cloud>& cloud, const glimpse::v1::PointCloud& msg) {
  if (!cloud) {
    if (cloud.error().message.empty()) __builtin_trap();
    return;
  }
  for (const auto& p : cloud->points)
    if (!p.allFinite()) __builtin_trap();
  if (glimpse::wire::PackPoints(cloud->points) != msg.xyz()) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace glimpse::server;
  namespace wire = glimpse::wire;
  namespace v1 = glimpse::v1;
  if (size < 1) return 0;
  const int kind = data[0] % 4;
  const auto* bytes = reinterpret_cast<const char*>(data + 1);
  const int n = static_cast<int>(size - 1);
  constexpr size_t kMaxPoints = 100'000;
  switch (kind) {
    case 0: {
      v1::ClassifyRequest req;
      if (!req.ParseFromArray(bytes, n)) return 0;
      (void)wire::ValidateModelName(req.model().name());
      (void)wire::MethodFromProto(req.method());
      CheckCloud(wire::CloudFromProto(req.cloud(), kMaxPoints), req.cloud());
      break;
    }
    case 1: {
      v1::ScanChunk chunk;
      if (!chunk.ParseFromArray(bytes, n)) return 0;
      (void)wire::MethodFromProto(chunk.method());
      CheckCloud(wire::CloudFromProto(chunk.cloud(), kMaxPoints), chunk.cloud());
      break;
    }
    case 2: {
      v1::TrainRequest msg;
      if (!msg.ParseFromArray(bytes, n)) return 0;
      Limits limits;
      limits.max_points_per_cloud = kMaxPoints;
      limits.max_train_points = 10 * kMaxPoints;
      TrainInput input;
      v1::TrainRequest header;
      header.mutable_header()->set_model_name("fuzz");
      if (!AddTrainRequest(header, limits, input).ok()) __builtin_trap();
      (void)AddTrainRequest(msg, limits, input);
      (void)AddTrainRequest(msg, limits, input);  // a second time: header twice, or a second cloud
      (void)CheckTrainInput(input);
      for (const auto& lc : input.clouds)
        if (lc.category.empty() || lc.object_id.empty()) __builtin_trap();
      break;
    }
    case 3: {
      v1::TrainHeader header;
      if (!header.ParseFromArray(bytes, n)) return 0;
      auto spec = wire::TrainSpecFromProto(header);
      if (spec) (void)wire::ToTrainParams(*spec);
      break;
    }
  }
  return 0;
}

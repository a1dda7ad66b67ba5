// The reliability tests' server: GlimpseService with the real recogniser (CoreEngine) behind a real
// loopback port over a temporary SQLite file, as main.cc builds it; and training data from core's
// shape zoo (two HPR views of each of two shapes per category).
#pragma once

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>

#include <future>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/fast_training.h"
#include "common/temp_dir.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/hidden_point_removal.h"
#include "glimpse/views/zoo.h"
#include "proto/wire/clouds.h"
#include "proto/wire/errors.h"
#include "server/server.h"
#include "server/service.h"

namespace glimpse::reliability {

using glimpse::testing::FastTrainHeader;
using glimpse::testing::TempDir;
using server::Limits;

struct RealServer {
  RealServer(const std::string& db, Limits limits) {
    auto opened = server::ModelStore::Open(db);
    if (!opened) throw std::runtime_error(opened.error().message);
    store = std::move(*opened);
    server::ServiceOptions o;
    o.store = store.get();
    o.engine = server::CoreEngine();
    o.limits = limits;
    o.metrics = &metrics;
    o.log = [this](const server::RequestLog& l) {
      std::lock_guard lock(log_mutex);
      logs.push_back(l);
    };
    service = std::make_unique<server::GlimpseService>(std::move(o));
    server::GrpcServerOptions g;
    g.address = "127.0.0.1:0";
    g.threads = static_cast<int>(limits.max_concurrent_streams) + 8;
    g.max_message_bytes = limits.max_message_bytes;
    auto started = server::StartGrpcServer(g, service.get());
    if (!started) throw std::runtime_error(started.error().message);
    running = std::move(*started);
    grpc::ChannelArguments args;
    args.SetMaxSendMessageSize(256 << 20);  // the client may send more than the server takes
    args.SetMaxReceiveMessageSize(256 << 20);
    channel = grpc::CreateCustomChannel("127.0.0.1:" + std::to_string(running.port),
                                        grpc::InsecureChannelCredentials(), args);
    stub = v1::Glimpse::NewStub(channel);
  }
  ~RealServer() {
    if (running.server) server::ShutdownGrpcServer(*running.server, std::chrono::seconds(5));
  }
  std::vector<server::RequestLog> Logs() {
    std::lock_guard lock(log_mutex);
    return logs;
  }

  std::unique_ptr<server::ModelStore> store;
  server::Metrics metrics;
  std::mutex log_mutex;
  std::vector<server::RequestLog> logs;
  std::unique_ptr<server::GlimpseService> service;
  server::RunningServer running;
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<v1::Glimpse::Stub> stub;
};

// Single views of zoo shapes: `views` of the paper's six viewpoints (0, 3, 1, 4, ...) per shape.
inline std::vector<TrainingCloud> ZooViews(size_t per_category, uint64_t seed, int views, size_t vertices = 3000) {
  std::vector<TrainingCloud> out;
  ZooOptions options;
  options.target_vertices = vertices;
  for (const LabelledMesh& m : make_zoo(per_category, seed, options)) {
    const Cloud full = mesh_vertices(m.mesh);
    const std::vector<Vec3> cameras = paper_viewpoints(full.points);
    for (int v = 0; v < views && v < int(cameras.size()); ++v) {
      const size_t which = static_cast<size_t>((v % 2) * 3 + v / 2) % cameras.size();
      out.push_back({m.category, m.category + "-" + std::to_string(m.seed),
                     hidden_point_removal(full.points, cameras[which])});
    }
  }
  return out;
}

inline v1::TrainRequest CloudMessage(const TrainingCloud& lc) {
  v1::TrainRequest req;
  req.mutable_cloud()->set_category(lc.category);
  req.mutable_cloud()->set_object_id(lc.object_id);
  *req.mutable_cloud()->mutable_cloud() = wire::CloudToProto(lc.cloud);
  return req;
}

// Sends the messages, closes the stream, reads every progress message; the call's status.
inline grpc::Status TrainStream(v1::Glimpse::Stub& stub, const std::vector<v1::TrainRequest>& messages,
                                v1::TrainProgress* last = nullptr,
                                std::chrono::milliseconds deadline = std::chrono::minutes(5)) {
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + deadline);
  auto stream = stub.Train(&ctx);
  for (const auto& m : messages)
    if (!stream->Write(m)) break;
  stream->WritesDone();
  for (v1::TrainProgress p; stream->Read(&p);)
    if (last) *last = p;
  return stream->Finish();
}

inline std::vector<v1::TrainRequest> TrainMessages(const v1::TrainHeader& header, const std::vector<TrainingCloud>& data) {
  std::vector<v1::TrainRequest> msgs(1);
  *msgs[0].mutable_header() = header;
  for (const TrainingCloud& lc : data) msgs.push_back(CloudMessage(lc));
  return msgs;
}

// grpc.health.v1.Health/Check of the whole server, by hand-encoded bytes (Debian installs no
// health.proto): 1 SERVING, 2 NOT_SERVING; -1 when the call failed.
inline int HealthStatus(const std::shared_ptr<grpc::Channel>& channel) {
  grpc::GenericStub stub(channel);
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
  grpc::ByteBuffer request, response;
  grpc::Slice empty("");
  request = grpc::ByteBuffer(&empty, 1);
  std::promise<grpc::Status> done;
  stub.UnaryCall(&ctx, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                 [&](grpc::Status s) { done.set_value(s); });
  if (!done.get_future().get().ok()) return -1;
  grpc::Slice slice;
  if (!response.DumpToSingleSlice(&slice).ok()) return -1;
  const std::string bytes(reinterpret_cast<const char*>(slice.begin()), slice.size());
  // HealthCheckResponse { ServingStatus status = 1; }: tag 0x08, one varint byte; UNKNOWN (0) is empty.
  return bytes.size() == 2 && bytes[0] == 0x08 ? bytes[1] : 0;
}

}  // namespace glimpse::reliability

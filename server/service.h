// GlimpseService: the glimpse.v1.Glimpse RPCs as a thin translation between messages and core calls.
// Each RPC reads its deadline/cancellation, calls core (through Options::engine) and the store, maps
// the result with wire::ToGrpcStatus, then records metrics and one log line. No exception leaves an RPC.
// The RPCs' domain logic is outside the class (batch.h, stream_classify.h, train.h), the conversions in
// the wire library (proto/wire) and convert.h.
#pragma once

#include <chrono>
#include <memory>
#include <string_view>
#include <thread>

#include "engine.h"
#include "glimpse/v1/glimpse.grpc.pb.h"
#include "limits.h"
#include "log.h"
#include "metrics.h"
#include "model_cache.h"
#include "security.h"
#include "store.h"

namespace glimpse::server {

struct ServiceOptions {
  ModelStore* store = nullptr;  // required; outlives the service
  Engine engine;                // CoreEngine() in the server; fakes in tests
  Limits limits;
  Metrics* metrics = nullptr;   // optional
  LogFn log = LogToStderr;      // optional
  SteadyClock clock;            // default: std::chrono::steady_clock::now
  // How often a watchdog cancels streams past limits.max_stream_duration; 0: no watchdog thread
  // (tests call streams().Reap()).
  std::chrono::milliseconds reap_interval{1000};
  // Non-empty: Train, DeleteModel and SetDefaultModel need `authorization: Bearer <auth_token>`
  // (UNAUTHENTICATED otherwise); the other RPCs stay open.
  std::string auth_token;
};

class GlimpseService final : public v1::Glimpse::Service {
 public:
  explicit GlimpseService(ServiceOptions options);
  ~GlimpseService() override;

  grpc::Status Train(grpc::ServerContext* ctx,
                     grpc::ServerReaderWriter<v1::TrainProgress, v1::TrainRequest>* stream) override;
  grpc::Status Classify(grpc::ServerContext* ctx, const v1::ClassifyRequest* request,
                        v1::ClassifyResponse* response) override;
  grpc::Status ClassifyBatch(grpc::ServerContext* ctx, const v1::ClassifyBatchRequest* request,
                             v1::ClassifyBatchResponse* response) override;
  grpc::Status StreamClassify(grpc::ServerContext* ctx,
                              grpc::ServerReaderWriter<v1::Decision, v1::ScanChunk>* stream) override;
  grpc::Status ClassifyScene(grpc::ServerContext* ctx, const v1::ClassifySceneRequest* request,
                             v1::ClassifySceneResponse* response) override;
  grpc::Status ListModels(grpc::ServerContext* ctx, const v1::ListModelsRequest* request,
                          v1::ListModelsResponse* response) override;
  grpc::Status GetModel(grpc::ServerContext* ctx, const v1::GetModelRequest* request,
                        v1::ModelInfo* response) override;
  grpc::Status DeleteModel(grpc::ServerContext* ctx, const v1::DeleteModelRequest* request,
                           v1::DeleteModelResponse* response) override;
  grpc::Status SetDefaultModel(grpc::ServerContext* ctx, const v1::SetDefaultModelRequest* request,
                               v1::ModelInfo* response) override;

  StreamRegistry& streams() { return streams_; }
  ModelCache& cache() { return cache_; }

 private:
  enum class Access { kOpen, kMutating };
  // The RPC boundary: checks the caller may make a mutating call, runs body, catches anything
  // thrown, maps the status, records metrics and logs.
  template <class Body>
  grpc::Status Handle(grpc::ServerContext* ctx, std::string_view rpc, Access access, RequestLog& log, Body&& body);
  Expected<StreamRegistry::Ticket> OpenStream(grpc::ServerContext* ctx);
  // Re-decides "unknown" of every answered result at a request's operating point (0: the model's default).
  Status SetKnownAcceptance(const Model& model, std::vector<Expected<Classification>>& results,
                            double known_acceptance) const;

  ServiceOptions options_;
  BearerToken token_;
  ModelCache cache_;
  StreamRegistry streams_;
  std::jthread watchdog_;
};

// Stops the work when the caller cancels or the deadline passes (core polls it).
CancelFn CancelFor(const grpc::ServerContext* ctx);
bool DeadlinePassed(const grpc::ServerContext* ctx);

}  // namespace glimpse::server

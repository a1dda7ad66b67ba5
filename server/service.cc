#include "service.h"

#include <grpcpp/server_context.h>

#include <condition_variable>
#include <exception>
#include <mutex>

#include "batch.h"
#include "convert.h"
#include "proto/wire/clouds.h"
#include "proto/wire/errors.h"
#include "proto/wire/methods.h"
#include "proto/wire/model_names.h"
#include "scene.h"
#include "stream_classify.h"
#include "train.h"

namespace glimpse::server {
namespace {

Error StreamTooLong(const Limits& limits) {
  return resource_exhausted("the stream ran longer than the limit of " +
                            std::to_string(limits.max_stream_duration.count()) + " s");
}

Error CancelledBeforeClassification() {
  return cancelled("the caller cancelled or the deadline passed before classification");
}

}  // namespace

CancelFn CancelFor(const grpc::ServerContext* ctx) {
  return [ctx] { return ctx->IsCancelled() || DeadlinePassed(ctx); };
}

bool DeadlinePassed(const grpc::ServerContext* ctx) {
  const auto deadline = ctx->deadline();
  return deadline != std::chrono::system_clock::time_point::max() && std::chrono::system_clock::now() >= deadline;
}

GlimpseService::GlimpseService(ServiceOptions options)
    : options_(std::move(options)),
      token_(options_.auth_token),
      cache_(*options_.store, options_.engine.deserialize, options_.limits.max_cached_models),
      streams_(options_.limits.max_concurrent_streams, options_.limits.max_stream_duration, options_.clock) {
  if (!options_.clock) options_.clock = [] { return std::chrono::steady_clock::now(); };
  if (options_.reap_interval.count() > 0) {
    watchdog_ = std::jthread([this](std::stop_token stop) {
      std::mutex m;
      std::condition_variable_any cv;
      std::unique_lock lock(m);
      while (!stop.stop_requested()) {
        cv.wait_for(lock, stop, options_.reap_interval, [] { return false; });
        if (!stop.stop_requested()) streams_.Reap();
      }
    });
  }
}

GlimpseService::~GlimpseService() = default;  // jthread: stop + join

template <class Body>
grpc::Status GlimpseService::Handle(grpc::ServerContext* ctx, std::string_view rpc, Access access, RequestLog& log,
                                    Body&& body) {
  const auto start = options_.clock();
  log.rpc = std::string(rpc);
  log.peer = ctx->peer();
  grpc::Status status;
  if (access == Access::kMutating && !token_.Accepts(ctx->client_metadata())) {
    // Before any work or store access; the message never echoes what was presented.
    status = grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                          std::string(rpc) + " needs the metadata 'authorization: Bearer <token>' with the server's token");
  } else {
    Status result;
    try {
      result = body();
    } catch (const std::exception& e) {
      result = internal_error(std::string("unexpected exception: ") + e.what());
    } catch (...) {
      result = internal_error("unexpected exception");
    }
    status = result.ok() ? grpc::Status::OK : wire::ToGrpcStatus(result.error(), DeadlinePassed(ctx));
  }
  try {
    const double ms = MsSince(start, options_.clock());
    if (options_.metrics) {
      options_.metrics->RecordRpc(rpc, status.error_code(), ms / 1000.0);
      options_.metrics->SetModelsLoaded(cache_.size());
    }
    if (options_.log) {
      log.latency_ms = ms;
      log.code = wire::StatusCodeName(status.error_code());
      log.message = status.error_message();
      options_.log(log);
    }
  } catch (...) {  // metrics and logs must not turn a finished call into a crash
  }
  return status;
}

Status GlimpseService::SetKnownAcceptance(const Model& model, std::vector<Expected<Classification>>& results,
                                          double known_acceptance) const {
  if (known_acceptance <= 0 || !options_.engine.set_known_acceptance) return {};
  for (Expected<Classification>& r : results)
    if (r)
      if (Status s = options_.engine.set_known_acceptance(model, *r, known_acceptance); !s.ok()) return s;
  return {};
}

Expected<StreamRegistry::Ticket> GlimpseService::OpenStream(grpc::ServerContext* ctx) {
  return streams_.Admit([ctx] { ctx->TryCancel(); });
}

grpc::Status GlimpseService::Classify(grpc::ServerContext* ctx, const v1::ClassifyRequest* request,
                                      v1::ClassifyResponse* response) {
  RequestLog log;
  return Handle(ctx, "Classify", Access::kOpen, log, [&]() -> Status {
    const auto start = options_.clock();
    log.model = LogModelRef(request->model().name(), request->model().version());
    auto ask = ClassifyAskFromProto(request->model(), request->method(), request->known_acceptance(), &log.method);
    if (!ask) return ask.error();
    auto cloud = wire::CloudFromProto(request->cloud(), options_.limits.max_points_per_cloud);
    if (!cloud) return cloud.error();
    log.points = cloud->points.size();
    auto loaded = cache_.Load(request->model().name(), request->model().version());
    if (!loaded) return loaded.error();
    log.model = LogModelRef(loaded->record.name, loaded->record.version);
    // Core polls the CancelFn only after feature extraction: do not start work nobody waits for.
    if (CancelFor(ctx)()) return CancelledBeforeClassification();
    auto result = options_.engine.classify(*loaded->model, *cloud, ask->method, CancelFor(ctx));
    if (!result) return result.error();
    if (ask->known_acceptance > 0 && options_.engine.set_known_acceptance)
      if (Status s = options_.engine.set_known_acceptance(*loaded->model, *result, ask->known_acceptance); !s.ok())
        return s;
    ToProto(*result, response);
    ToProto(loaded->record, response->mutable_model());
    response->set_model_id(static_cast<uint64_t>(loaded->record.id));
    response->mutable_timings()->set_model_load_ms(loaded->load_ms);
    response->mutable_timings()->set_total_ms(MsSince(start, options_.clock()));
    log.method = wire::MethodName(result->method);
    return {};
  });
}

grpc::Status GlimpseService::ClassifyBatch(grpc::ServerContext* ctx, const v1::ClassifyBatchRequest* request,
                                           v1::ClassifyBatchResponse* response) {
  RequestLog log;
  return Handle(ctx, "ClassifyBatch", Access::kOpen, log, [&]() -> Status {
    const auto start = options_.clock();
    log.model = LogModelRef(request->model().name(), request->model().version());
    log.messages = static_cast<uint64_t>(request->clouds_size());
    auto ask = ClassifyAskFromProto(request->model(), request->method(), request->known_acceptance(), &log.method);
    if (!ask) return ask.error();
    auto batch = UnpackBatch(*request, options_.limits);
    if (!batch) return batch.error();
    log.points = batch->points;
    auto loaded = cache_.Load(request->model().name(), request->model().version());
    if (!loaded) return loaded.error();
    log.model = LogModelRef(loaded->record.name, loaded->record.version);
    // What concerns every cloud fails the call, not each result.
    const MethodId used = ask->method.value_or(loaded->model->default_method);
    if (Status s = check_trained_for(*loaded->model, used); !s.ok()) return s.error();
    if (CancelFor(ctx)()) return CancelledBeforeClassification();
    auto results = options_.engine.classify_batch(*loaded->model, batch->clouds, ask->method, CancelFor(ctx));
    if (Status s = CheckBatchResults(results); !s.ok()) return s;
    if (Status s = SetKnownAcceptance(*loaded->model, results, ask->known_acceptance); !s.ok()) return s;
    FillBatchResponse(*batch, results, loaded->record, loaded->load_ms, response);
    ToProto(loaded->record, response->mutable_model());
    response->set_method(wire::MethodToProto(used));
    response->set_total_ms(MsSince(start, options_.clock()));
    log.method = wire::MethodName(used);
    return {};
  });
}

grpc::Status GlimpseService::ClassifyScene(grpc::ServerContext* ctx, const v1::ClassifySceneRequest* request,
                                           v1::ClassifySceneResponse* response) {
  RequestLog log;
  return Handle(ctx, "ClassifyScene", Access::kOpen, log, [&]() -> Status {
    const auto start = options_.clock();
    log.model = LogModelRef(request->model().name(), request->model().version());
    if (!options_.engine.segment_scene) return internal_error("the server's engine cannot split scenes");
    auto ask = ClassifyAskFromProto(request->model(), request->method(), request->known_acceptance(), &log.method);
    if (!ask) return ask.error();
    auto params = SceneParamsFromProto(request->scene());
    if (!params) return params.error();
    auto frame = wire::CloudFromProto(request->frame(), options_.limits.max_points_per_cloud);
    if (!frame) return Error{frame.error().code, "the frame: " + frame.error().message};
    log.points = frame->points.size();
    auto loaded = cache_.Load(request->model().name(), request->model().version());
    if (!loaded) return loaded.error();
    log.model = LogModelRef(loaded->record.name, loaded->record.version);
    const MethodId used = ask->method.value_or(loaded->model->default_method);
    if (Status s = check_trained_for(*loaded->model, used); !s.ok()) return s.error();
    if (CancelFor(ctx)()) return CancelledBeforeClassification();
    const auto segment_start = options_.clock();
    auto scene = options_.engine.segment_scene(*frame, *params);
    if (!scene) return scene.error();
    response->set_segment_ms(MsSince(segment_start, options_.clock()));
    std::vector<Cloud> objects;
    for (const SceneObject& o : scene->objects) objects.push_back(object_cloud(*frame, o));
    auto results = options_.engine.classify_batch(*loaded->model, objects, ask->method, CancelFor(ctx));
    if (Status s = CheckBatchResults(results); !s.ok()) return s;
    if (Status s = SetKnownAcceptance(*loaded->model, results, ask->known_acceptance); !s.ok()) return s;
    FillSceneResponse(*scene, results, loaded->record, loaded->load_ms, request->return_indices(), response);
    ToProto(loaded->record, response->mutable_model());
    response->set_method(wire::MethodToProto(used));
    response->set_total_ms(MsSince(start, options_.clock()));
    log.method = wire::MethodName(used);
    return {};
  });
}

grpc::Status GlimpseService::StreamClassify(grpc::ServerContext* ctx,
                                            grpc::ServerReaderWriter<v1::Decision, v1::ScanChunk>* stream) {
  RequestLog log;
  return Handle(ctx, "StreamClassify", Access::kOpen, log, [&]() -> Status {
    auto ticket = OpenStream(ctx);
    if (!ticket) return ticket.error();
    const Metrics::ActiveStream active(options_.metrics, "StreamClassify");
    ScanStream scan(cache_, options_.engine, options_.limits, options_.clock, log);
    bool caller_left = false;
    for (v1::ScanChunk chunk; !caller_left && stream->Read(&chunk);) {
      ++log.messages;
      if (ticket->over_time()) return StreamTooLong(options_.limits);
      auto reply = scan.Add(chunk, log.messages - 1);
      if (!reply) return reply.error();
      caller_left = !stream->Write(*reply);
    }
    if (ticket->expired()) return StreamTooLong(options_.limits);
    if (ctx->IsCancelled()) return cancelled("the caller cancelled the stream");
    if (caller_left) return {};
    // The scanner is done (WritesDone): the final answer, every feature on the whole scan, is Classify's.
    auto final_decision = scan.Finish(log.messages - 1);
    if (!final_decision) return final_decision.error();
    stream->Write(*final_decision);
    return {};
  });
}

grpc::Status GlimpseService::Train(grpc::ServerContext* ctx,
                                   grpc::ServerReaderWriter<v1::TrainProgress, v1::TrainRequest>* stream) {
  RequestLog log;
  return Handle(ctx, "Train", Access::kMutating, log, [&]() -> Status {
    auto ticket = OpenStream(ctx);
    if (!ticket) return ticket.error();
    const Metrics::ActiveStream active(options_.metrics, "Train");
    TrainInput input;
    for (v1::TrainRequest msg; stream->Read(&msg);) {
      ++log.messages;
      if (ticket->over_time()) return StreamTooLong(options_.limits);
      if (Status s = AddTrainRequest(msg, options_.limits, input); !s.ok()) return s;
      log.model = input.name;
      log.points = input.points;
      // No progress while receiving: a client that writes everything before reading would block a
      // server Write (always, on an in-process channel), and the server would stop reading.
    }
    if (ticket->expired()) return StreamTooLong(options_.limits);
    if (ctx->IsCancelled() || DeadlinePassed(ctx)) return cancelled("the caller cancelled Train while sending");
    ticket->disarm();  // training itself is bounded by the caller's deadline
    if (Status s = CheckTrainInput(input); !s.ok()) return s;
    TrainProgressWriter progress([stream](const v1::TrainProgress& p) { return stream->Write(p); });
    progress.Received(input.clouds.size());
    auto record = TrainAndStore(
        input, options_.engine, *options_.store, [&](const TrainingProgress& p) { progress.Update(p); },
        CancelFor(ctx), [&](double share) { progress.SetFeaturesPercent(share); });
    if (!record) return record.error();
    log.model = LogModelRef(record->name, record->version);
    progress.Done(*record);
    return {};
  });
}

grpc::Status GlimpseService::ListModels(grpc::ServerContext* ctx, const v1::ListModelsRequest* request,
                                        v1::ListModelsResponse* response) {
  RequestLog log;
  return Handle(ctx, "ListModels", Access::kOpen, log, [&]() -> Status {
    log.model = request->name();
    if (!request->name().empty())
      if (Status s = wire::ValidateModelName(request->name()); !s.ok()) return s;
    auto records = options_.store->List(request->name());
    if (!records) return records.error();
    for (const ModelRecord& r : *records) ToProto(r, response->add_models());
    return {};
  });
}

grpc::Status GlimpseService::GetModel(grpc::ServerContext* ctx, const v1::GetModelRequest* request,
                                      v1::ModelInfo* response) {
  RequestLog log;
  return Handle(ctx, "GetModel", Access::kOpen, log, [&]() -> Status {
    log.model = LogModelRef(request->model().name(), request->model().version());
    if (Status s = wire::ValidateModelName(request->model().name()); !s.ok()) return s;
    auto record = options_.store->Get(request->model().name(), request->model().version());
    if (!record) return record.error();
    ToProto(*record, response);
    return {};
  });
}

grpc::Status GlimpseService::DeleteModel(grpc::ServerContext* ctx, const v1::DeleteModelRequest* request,
                                         v1::DeleteModelResponse* response) {
  RequestLog log;
  return Handle(ctx, "DeleteModel", Access::kMutating, log, [&]() -> Status {
    log.model = LogModelRef(request->name(), request->version());
    if (Status s = wire::ValidateModelName(request->name()); !s.ok()) return s;
    auto deleted = options_.store->Delete(request->name(), request->version());
    if (!deleted) return deleted.error();
    cache_.Sweep();
    for (uint32_t v : *deleted) response->add_deleted_versions(v);
    return {};
  });
}

grpc::Status GlimpseService::SetDefaultModel(grpc::ServerContext* ctx, const v1::SetDefaultModelRequest* request,
                                             v1::ModelInfo* response) {
  RequestLog log;
  return Handle(ctx, "SetDefaultModel", Access::kMutating, log, [&]() -> Status {
    log.model = LogModelRef(request->name(), request->version());
    if (Status s = wire::ValidateModelName(request->name()); !s.ok()) return s;
    auto record = options_.store->SetDefault(request->name(), request->version());
    if (!record) return record.error();
    ToProto(*record, response);
    return {};
  });
}

}  // namespace glimpse::server

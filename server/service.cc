#include "service.h"

#include <grpcpp/server_context.h>

#include <condition_variable>
#include <algorithm>
#include <exception>
#include <mutex>

#include "batch.h"
#include "convert.h"
#include "train.h"

namespace glimpse::server {
namespace {

double MsSince(std::chrono::steady_clock::time_point start, std::chrono::steady_clock::time_point now) {
  return std::chrono::duration<double, std::milli>(now - start).count();
}

std::string RefText(std::string_view name, uint32_t version) {
  return version ? std::string(name) + "@" + std::to_string(version) : std::string(name);
}

const char* MethodText(const std::optional<MethodId>& m) {
  return m ? method_name(*m) : "default";
}

Error StreamTooLong(const Limits& limits) {
  return resource_exhausted("the stream ran longer than the limit of " +
                            std::to_string(limits.max_stream_duration.count()) + " s");
}

void FillRef(const ModelRecord& r, v1::ModelRef* ref) {
  ref->set_name(r.name);
  ref->set_version(r.version);
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
    status = result.ok() ? grpc::Status::OK : ToGrpcStatus(result.error(), DeadlinePassed(ctx));
  }
  try {
    const double ms = MsSince(start, options_.clock());
    if (options_.metrics) {
      options_.metrics->RecordRpc(rpc, status.error_code(), ms / 1000.0);
      options_.metrics->SetModelsLoaded(cache_.size());
    }
    if (options_.log) {
      log.latency_ms = ms;
      log.code = StatusCodeName(status.error_code());
      log.message = status.error_message();
      options_.log(log);
    }
  } catch (...) {  // metrics and logs must not turn a finished call into a crash
  }
  return status;
}

Expected<StreamRegistry::Ticket> GlimpseService::OpenStream(grpc::ServerContext* ctx) {
  return streams_.Admit([ctx] { ctx->TryCancel(); });
}

grpc::Status GlimpseService::Classify(grpc::ServerContext* ctx, const v1::ClassifyRequest* request,
                                      v1::ClassifyResponse* response) {
  RequestLog log;
  return Handle(ctx, "Classify", Access::kOpen, log, [&]() -> Status {
    const auto start = options_.clock();
    log.model = RefText(request->model().name(), request->model().version());
    if (Status s = ValidateModelName(request->model().name()); !s.ok()) return s;
    auto method = MethodFromProto(request->method());
    if (!method) return method.error();
    log.method = MethodText(*method);
    auto acceptance = KnownAcceptanceFromProto(request->known_acceptance());
    if (!acceptance) return acceptance.error();
    auto cloud = CloudFromProto(request->cloud(), options_.limits.max_points_per_cloud);
    if (!cloud) return cloud.error();
    log.points = cloud->points.size();
    auto loaded = cache_.Load(request->model().name(), request->model().version());
    if (!loaded) return loaded.error();
    log.model = RefText(loaded->record.name, loaded->record.version);
    // Core polls the CancelFn only after feature extraction: do not start work nobody waits for.
    if (CancelFor(ctx)()) return cancelled("the caller cancelled or the deadline passed before classification");
    auto result = options_.engine.classify(*loaded->model, *cloud, *method, CancelFor(ctx));
    if (!result) return result.error();
    if (*acceptance > 0 && options_.engine.set_known_acceptance)
      if (Status s = options_.engine.set_known_acceptance(*loaded->model, *result, *acceptance); !s.ok()) return s;
    ToProto(*result, response);
    FillRef(loaded->record, response->mutable_model());
    response->set_model_id(static_cast<uint64_t>(loaded->record.id));
    response->mutable_timings()->set_model_load_ms(loaded->load_ms);
    response->mutable_timings()->set_total_ms(MsSince(start, options_.clock()));
    log.method = MethodText(result->method);
    return {};
  });
}

grpc::Status GlimpseService::ClassifyBatch(grpc::ServerContext* ctx, const v1::ClassifyBatchRequest* request,
                                           v1::ClassifyBatchResponse* response) {
  RequestLog log;
  return Handle(ctx, "ClassifyBatch", Access::kOpen, log, [&]() -> Status {
    const auto start = options_.clock();
    log.model = RefText(request->model().name(), request->model().version());
    log.messages = static_cast<uint64_t>(request->clouds_size());
    if (Status s = ValidateModelName(request->model().name()); !s.ok()) return s;
    auto method = MethodFromProto(request->method());
    if (!method) return method.error();
    log.method = MethodText(*method);
    auto acceptance = KnownAcceptanceFromProto(request->known_acceptance());
    if (!acceptance) return acceptance.error();
    auto batch = UnpackBatch(*request, options_.limits);
    if (!batch) return batch.error();
    log.points = batch->points;
    auto loaded = cache_.Load(request->model().name(), request->model().version());
    if (!loaded) return loaded.error();
    log.model = RefText(loaded->record.name, loaded->record.version);
    // What concerns every cloud fails the call, not each result.
    const MethodId used = method->value_or(loaded->model->default_method);
    if (Status s = check_trained_for(*loaded->model, used); !s.ok()) return s.error();
    if (CancelFor(ctx)()) return cancelled("the caller cancelled or the deadline passed before classification");
    std::vector<Expected<Classification>> results = options_.engine.classify_batch(*loaded->model, batch->clouds, *method, CancelFor(ctx));
    for (const Expected<Classification>& r : results)
      if (!r && (r.error().code == ErrorCode::kCancelled || r.error().code == ErrorCode::kFailedPrecondition))
        return r.error();  // the call was stopped, or the model cannot classify at all (its feature version)
    if (*acceptance > 0 && options_.engine.set_known_acceptance)
      for (Expected<Classification>& r : results)
        if (r)
          if (Status s = options_.engine.set_known_acceptance(*loaded->model, *r, *acceptance); !s.ok()) return s;
    FillBatchResponse(*batch, results, loaded->record, loaded->load_ms, response);
    FillRef(loaded->record, response->mutable_model());
    response->set_method(MethodToProto(used));
    response->set_total_ms(MsSince(start, options_.clock()));
    log.method = MethodText(used);
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

    std::unique_ptr<ScanSession> session;
    LoadedModel model;
    MethodId method = MethodId::kFusion;
    double known_acceptance = 0;
    v1::ScanChunk chunk;
    bool caller_left = false;
    while (stream->Read(&chunk)) {
      const auto start = options_.clock();
      ++log.messages;
      if (ticket->over_time()) return StreamTooLong(options_.limits);
      if (!session) {
        log.model = RefText(chunk.model().name(), chunk.model().version());
        if (Status s = ValidateModelName(chunk.model().name()); !s.ok()) return s;
        auto m = MethodFromProto(chunk.method());
        if (!m) return m.error();
        auto acceptance = KnownAcceptanceFromProto(chunk.known_acceptance());
        if (!acceptance) return acceptance.error();
        known_acceptance = *acceptance;
        auto loaded = cache_.Load(chunk.model().name(), chunk.model().version());
        if (!loaded) return loaded.error();
        model = std::move(*loaded);
        method = m->value_or(model.model->default_method);
        log.model = RefText(model.record.name, model.record.version);
        log.method = MethodText(method);
        SessionParams params;
        params.method = *m;
        params.max_points = options_.limits.max_session_points;
        params.max_chunks = options_.limits.max_session_chunks;
        params.max_chunk_points = options_.limits.max_points_per_cloud;
        params.known_acceptance = known_acceptance;
        auto created = options_.engine.create_session(model.model, params);
        if (!created) return created.error();
        session = std::move(*created);
      } else {
        const v1::ModelRef& ref = chunk.model();
        bool same_model = ref.name().empty() || (ref.name() == model.record.name &&
                                                 (ref.version() == 0 || ref.version() == model.record.version));
        auto m = MethodFromProto(chunk.method());
        bool same_method = m.ok() && (!*m || **m == method);
        const double a = chunk.known_acceptance();
        if (!same_model || !same_method || (a != 0 && a != known_acceptance))
          return invalid_argument("only the first chunk chooses the model, method and known acceptance; chunk " +
                                  std::to_string(log.messages - 1) + " names others");
      }
      auto cloud = CloudFromProto(chunk.cloud(), options_.limits.max_points_per_cloud);
      if (!cloud) return Error{cloud.error().code, "chunk " + std::to_string(log.messages - 1) + ": " + cloud.error().message};
      log.points += cloud->points.size();
      StreamDecision decision;
      if (cloud->points.empty()) {
        decision = session->last();  // nothing new to fuse (e.g. a first chunk that only names the model)
      } else {
        auto added = session->add(*cloud);
        if (!added) return added.error();
        decision = std::move(*added);
      }
      v1::Decision reply;
      ToProto(decision, &reply);
      reply.set_chunk_index(log.messages - 1);  // the message answered (the session counts only non-empty ones)
      FillRef(model.record, reply.mutable_model());
      reply.set_method(MethodToProto(method));
      reply.set_latency_ms(MsSince(start, options_.clock()));
      if (!stream->Write(reply)) {  // the caller went away
        caller_left = true;
        break;
      }
    }
    if (ticket->expired()) return StreamTooLong(options_.limits);
    if (ctx->IsCancelled()) return cancelled("the caller cancelled the stream");
    // A stream closed before its first chunk asked nothing: an error, not an OK with nothing decided.
    if (!session && !caller_left) return invalid_argument("the stream ended before its first chunk: nothing to classify");
    // The scanner is done (WritesDone): the final answer, every feature on the whole scan, is Classify's.
    if (session && !caller_left) {
      // A scan that never gave a decision ends in an error, as Classify's of too few points does, not
      // in an OK with nothing decided.
      if (session->last().raw_scores.empty())
        return invalid_argument("the scan ended without a decision: its " + std::to_string(session->last().points) +
                                (session->last().points == 1 ? " point" : " points") +
                                " gave no surface to judge (too few, or all on a line)");
      const auto start = options_.clock();
      auto finished = session->finish();
      if (!finished) return finished.error();
      v1::Decision reply;
      ToProto(*finished, &reply);
      reply.set_chunk_index(log.messages - 1);
      FillRef(model.record, reply.mutable_model());
      reply.set_method(MethodToProto(method));
      reply.set_latency_ms(MsSince(start, options_.clock()));
      stream->Write(reply);
    }
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
    v1::TrainRequest msg;
    while (stream->Read(&msg)) {
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

    // Core may report progress from worker threads: one writer at a time, and only when it moved.
    std::mutex write_mutex;
    v1::TrainProgress last;
    last.set_stage("received");
    last.set_clouds_received(input.clouds.size());
    stream->Write(last);
    auto progress = [&](const TrainingProgress& p) {
      if (p.stage == "done") return;  // core's end; the call is done once the model is stored
      std::lock_guard lock(write_mutex);
      if (p.stage == "features") last.set_features_extracted(p.done);
      if (p.stage == "codebooks") {
        last.set_codebooks_fitted(p.done);
        last.set_codebooks_total(p.total);
      }
      double percent = std::max(last.percent(), std::min(99.0, TrainPercent(p.stage, p.done, p.total)));
      bool moved = p.stage != last.stage() || percent >= last.percent() + 1.0 || p.done == p.total;
      last.set_stage(p.stage);
      last.set_stage_done(p.done);
      last.set_stage_total(p.total);
      if (!moved) return;
      last.set_percent(percent);
      stream->Write(last);
    };
    auto record = TrainAndStore(input, options_.engine, *options_.store, progress, CancelFor(ctx));
    if (!record) return record.error();
    log.model = RefText(record->name, record->version);
    std::lock_guard lock(write_mutex);
    last.set_stage("done");
    last.set_stage_done(1);
    last.set_stage_total(1);
    last.set_percent(100);
    ToProto(*record, last.mutable_model());
    stream->Write(last);
    return {};
  });
}

grpc::Status GlimpseService::ListModels(grpc::ServerContext* ctx, const v1::ListModelsRequest* request,
                                        v1::ListModelsResponse* response) {
  RequestLog log;
  return Handle(ctx, "ListModels", Access::kOpen, log, [&]() -> Status {
    log.model = request->name();
    if (!request->name().empty())
      if (Status s = ValidateModelName(request->name()); !s.ok()) return s;
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
    log.model = RefText(request->model().name(), request->model().version());
    if (Status s = ValidateModelName(request->model().name()); !s.ok()) return s;
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
    log.model = RefText(request->name(), request->version());
    if (Status s = ValidateModelName(request->name()); !s.ok()) return s;
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
    log.model = RefText(request->name(), request->version());
    if (Status s = ValidateModelName(request->name()); !s.ok()) return s;
    auto record = options_.store->SetDefault(request->name(), request->version());
    if (!record) return record.error();
    ToProto(*record, response);
    return {};
  });
}

}  // namespace glimpse::server

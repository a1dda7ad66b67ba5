#include "stream_classify.h"

#include "convert.h"
#include "scene.h"
#include "proto/wire/clouds.h"
#include "proto/wire/methods.h"

namespace glimpse::server {

ScanStream::ScanStream(ModelCache& cache, const Engine& engine, const Limits& limits, SteadyClock clock,
                       RequestLog& log)
    : cache_(cache), engine_(engine), limits_(limits), clock_(std::move(clock)), log_(log) {}

Status ScanStream::Open(const v1::ScanChunk& first) {
  log_.model = LogModelRef(first.model().name(), first.model().version());
  auto ask = ClassifyAskFromProto(first.model(), first.method(), first.known_acceptance());
  if (!ask) return ask.error();
  known_acceptance_ = ask->known_acceptance;
  auto loaded = cache_.Load(first.model().name(), first.model().version());
  if (!loaded) return loaded.error();
  model_ = std::move(*loaded);
  method_ = ask->method.value_or(model_.model->default_method);
  log_.model = LogModelRef(model_.record.name, model_.record.version);
  log_.method = wire::MethodName(method_);
  SessionParams params;
  params.method = ask->method;
  params.max_points = limits_.max_session_points;
  params.max_chunks = limits_.max_session_chunks;
  params.max_chunk_points = limits_.max_points_per_cloud;
  params.known_acceptance = known_acceptance_;
  if (first.has_track()) {
    auto target = TrackTargetFromProto(first.track());
    if (!target) return target.error();
    auto scene = SceneParamsFromProto(first.scene());
    if (!scene) return scene.error();
    auto tracker = SceneTracker::create(*target, TrackParams{.scene = *scene});
    if (!tracker) return Error{tracker.error().code, "track: " + tracker.error().message};
    tracker_ = std::move(*tracker);
  } else if (first.has_scene()) {
    return invalid_argument("scene parameters split a tracking stream's frames: name a target (track) with them");
  }
  auto created = engine_.create_session(model_.model, params);
  if (!created) return created.error();
  session_ = std::move(*created);
  return {};
}

Status ScanStream::CheckSameSession(const v1::ScanChunk& chunk, uint64_t index) const {
  const v1::ModelRef& ref = chunk.model();
  const bool same_model = ref.name().empty() || (ref.name() == model_.record.name &&
                                                 (ref.version() == 0 || ref.version() == model_.record.version));
  auto m = wire::MethodFromProto(chunk.method());
  const bool same_method = m.ok() && (!*m || **m == method_);
  const double a = chunk.known_acceptance();
  if (!same_model || !same_method || (a != 0 && a != known_acceptance_))
    return invalid_argument("only the first chunk chooses the model, method and known acceptance; chunk " +
                            std::to_string(index) + " names others");
  if (chunk.has_track() || chunk.has_scene())
    return invalid_argument("only the first chunk names a target and its scene parameters; chunk " +
                            std::to_string(index) + " names them again");
  return {};
}

v1::Decision ScanStream::Reply(const StreamDecision& decision, uint64_t index,
                               std::chrono::steady_clock::time_point start) const {
  v1::Decision reply;
  ToProto(decision, &reply);
  reply.set_chunk_index(index);  // the message answered (the session counts only non-empty ones)
  ToProto(model_.record, reply.mutable_model());
  reply.set_method(wire::MethodToProto(method_));
  reply.set_latency_ms(MsSince(start, clock_()));
  return reply;
}

Expected<v1::Decision> ScanStream::Add(const v1::ScanChunk& chunk, uint64_t index) {
  const auto start = clock_();
  if (Status s = session_ ? CheckSameSession(chunk, index) : Open(chunk); !s.ok()) return s.error();
  auto cloud = wire::CloudFromProto(chunk.cloud(), limits_.max_points_per_cloud);
  if (!cloud) return Error{cloud.error().code, "chunk " + std::to_string(index) + ": " + cloud.error().message};
  log_.points += cloud->points.size();
  if (cloud->points.empty()) return Reply(session_->last(), index, start);  // nothing new to fuse
  if (tracker_) return AddFrame(*cloud, index, start);
  auto added = session_->add(*cloud);
  if (!added) return added.error();
  return Reply(*added, index, start);
}

Expected<v1::Decision> ScanStream::AddFrame(const Cloud& frame, uint64_t index,
                                            std::chrono::steady_clock::time_point start) {
  if (!frame.sensor)
    return invalid_argument("chunk " + std::to_string(index) +
                            ": a tracking stream's frames need their sensor (PointCloud.sensor): the target is "
                            "followed as the sensor moves");
  auto step = tracker_->next(frame);
  if (!step) return Error{step.error().code, "chunk " + std::to_string(index) + ": " + step.error().message};
  const StreamDecision* decision = &session_->last();
  Expected<StreamDecision> added = StreamDecision{};
  if (step->found && !step->fresh.empty()) {  // the target's surface this frame adds
    added = session_->add(Cloud{std::move(step->fresh), frame.sensor, frame.frame});
    if (!added) return added.error();
    decision = &*added;
  }
  v1::Decision reply = Reply(*decision, index, start);
  v1::TrackedObject* tracked = reply.mutable_tracked();
  tracked->set_found(step->found);
  tracked->set_objects(static_cast<uint32_t>(step->objects));
  if (step->found) ToProto(step->object, false, tracked->mutable_object());
  else tracked->set_not_found(step->not_found);
  return reply;
}

Expected<v1::Decision> ScanStream::Finish(uint64_t last_index) {
  // A stream closed before its first chunk asked nothing: an error, not an OK with nothing decided.
  if (!session_) return invalid_argument("the stream ended before its first chunk: nothing to classify");
  // A scan that never gave a decision ends in an error, as Classify's of too few points does.
  const StreamDecision& last = session_->last();
  if (last.raw_scores.empty())
    return invalid_argument("the scan ended without a decision: its " + std::to_string(last.points) +
                            (last.points == 1 ? " point" : " points") +
                            " gave no surface to judge (too few, or all on a line)");
  const auto start = clock_();
  auto finished = session_->finish();
  if (!finished) return finished.error();
  return Reply(*finished, last_index, start);
}

}  // namespace glimpse::server

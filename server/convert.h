// The server's messages <-> core types beyond the shared wire library (proto/wire: clouds, errors,
// methods, model names, training parameters): a request's operating point, and the replies built from
// core's results and the store's records. Every function here is pure (no I/O, no gRPC calls) so it can
// be unit-tested and fuzzed on its own.
#pragma once

#include <optional>
#include <string>

#include "engine.h"
#include "glimpse/v1/glimpse.pb.h"
#include "store.h"

namespace glimpse::server {

// What Classify, ClassifyBatch and a stream's first chunk ask for.
struct ClassifyAsk {
  std::optional<MethodId> method;  // nullopt: the model's default
  double known_acceptance = 0;     // 0: the model's default
};
// Checks the model name, the method and the operating point, in that order (INVALID_ARGUMENT).
// `method_log`, when given, gets the method's name as soon as it is read: a log line names it even when
// the operating point is refused.
Expected<ClassifyAsk> ClassifyAskFromProto(const v1::ModelRef& model, int method, double known_acceptance,
                                           std::string* method_log = nullptr);

// A request's operating point of "unknown": 0 (the model's default) or a share in (0, 1];
// INVALID_ARGUMENT otherwise (NaN included).
Expected<double> KnownAcceptanceFromProto(double known_acceptance);

void ToProto(const ModelRecord& record, v1::ModelInfo* out);
void ToProto(const Classification& c, v1::ClassifyResponse* out);
void ToProto(const StreamDecision& d, v1::Decision* out);
// The model a reply was answered with.
void ToProto(const ModelRecord& record, v1::ModelRef* out);

}  // namespace glimpse::server

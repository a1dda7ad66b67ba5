#include "metrics.h"

#include <string>

#include "proto/wire/errors.h"

namespace glimpse::server {

namespace {
// 1 ms .. ~2 min, roughly x2.5 apart: classification is milliseconds, training minutes.
const prometheus::Histogram::BucketBoundaries kLatencyBuckets = {
    0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 25, 60, 120};

template <class T>
double Value(prometheus::Family<T>& family, const prometheus::Labels& labels) {
  return family.Has(labels) ? family.Add(labels).Value() : 0;  // Add returns the existing series
}
}  // namespace

Metrics::Metrics(std::shared_ptr<prometheus::Registry> registry)
    : registry_(std::move(registry)),
      requests_(prometheus::BuildCounter()
                    .Name("glimpse_rpc_requests_total")
                    .Help("Finished RPCs by method and gRPC status code")
                    .Register(*registry_)),
      errors_(prometheus::BuildCounter()
                  .Name("glimpse_rpc_errors_total")
                  .Help("RPCs that finished with a status other than OK, by method and code")
                  .Register(*registry_)),
      latency_(prometheus::BuildHistogram()
                   .Name("glimpse_rpc_duration_seconds")
                   .Help("Server-side RPC latency by method")
                   .Register(*registry_)),
      active_streams_(prometheus::BuildGauge()
                          .Name("glimpse_active_streams")
                          .Help("Open streaming RPCs by method")
                          .Register(*registry_)),
      models_loaded_(prometheus::BuildGauge()
                         .Name("glimpse_models_loaded")
                         .Help("Deserialized models held in memory")
                         .Register(*registry_)
                         .Add({})) {}

void Metrics::RecordRpc(std::string_view rpc, grpc::StatusCode code, double seconds) {
  prometheus::Labels labels{{"method", std::string(rpc)}, {"code", wire::StatusCodeName(code)}};
  requests_.Add(labels).Increment();
  if (code != grpc::StatusCode::OK) errors_.Add(labels).Increment();
  latency_.Add({{"method", std::string(rpc)}}, kLatencyBuckets).Observe(seconds);
}

void Metrics::StreamOpened(std::string_view rpc) { active_streams_.Add({{"method", std::string(rpc)}}).Increment(); }
void Metrics::StreamClosed(std::string_view rpc) { active_streams_.Add({{"method", std::string(rpc)}}).Decrement(); }
void Metrics::SetModelsLoaded(size_t n) { models_loaded_.Set(static_cast<double>(n)); }

double Metrics::RequestCount(std::string_view rpc, grpc::StatusCode code) const {
  return Value(requests_, {{"method", std::string(rpc)}, {"code", wire::StatusCodeName(code)}});
}

double Metrics::ActiveStreams(std::string_view rpc) const {
  return Value(active_streams_, {{"method", std::string(rpc)}});
}

double Metrics::ModelsLoaded() const { return models_loaded_.Value(); }

}  // namespace glimpse::server

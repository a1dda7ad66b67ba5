// Prometheus metrics of the service: requests and errors by RPC and status code, latency histograms,
// active streams and models loaded. The registry is exposed over HTTP by main.cc; tests read it.
#pragma once

#include <grpcpp/support/status.h>
#include <prometheus/counter.h>
#include <prometheus/family.h>
#include <prometheus/gauge.h>
#include <prometheus/histogram.h>
#include <prometheus/registry.h>

#include <memory>
#include <string>
#include <string_view>

namespace glimpse::server {

class Metrics {
 public:
  explicit Metrics(std::shared_ptr<prometheus::Registry> registry = std::make_shared<prometheus::Registry>());

  void RecordRpc(std::string_view rpc, grpc::StatusCode code, double seconds);
  void StreamOpened(std::string_view rpc);
  void StreamClosed(std::string_view rpc);
  void SetModelsLoaded(size_t n);

  // An open stream of `rpc`, counted in the active streams gauge for as long as it lives (none without
  // metrics).
  class ActiveStream {
   public:
    ActiveStream(Metrics* metrics, std::string_view rpc) : metrics_(metrics), rpc_(rpc) {
      if (metrics_) metrics_->StreamOpened(rpc_);
    }
    ~ActiveStream() {
      if (metrics_) metrics_->StreamClosed(rpc_);
    }
    ActiveStream(const ActiveStream&) = delete;
    ActiveStream& operator=(const ActiveStream&) = delete;

   private:
    Metrics* metrics_;
    std::string rpc_;
  };

  const std::shared_ptr<prometheus::Registry>& registry() const { return registry_; }
  // For tests: the current value of a counter/gauge series (0 when absent).
  double RequestCount(std::string_view rpc, grpc::StatusCode code) const;
  double ActiveStreams(std::string_view rpc) const;
  double ModelsLoaded() const;

 private:
  std::shared_ptr<prometheus::Registry> registry_;
  prometheus::Family<prometheus::Counter>& requests_;
  prometheus::Family<prometheus::Counter>& errors_;
  prometheus::Family<prometheus::Histogram>& latency_;
  prometheus::Family<prometheus::Gauge>& active_streams_;
  prometheus::Gauge& models_loaded_;
};

}  // namespace glimpse::server

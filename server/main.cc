// glimpse-server: flags/environment -> model store -> metrics endpoint -> gRPC server; runs until
// SIGTERM/SIGINT, then drains in-flight calls and closes the store.
#include <prometheus/exposer.h>

#include <csignal>
#include <cstdio>
#include <exception>
#include <memory>
#include <pthread.h>

#include "config.h"
#include "cpus.h"
#include "engine.h"
#include "log.h"
#include "metrics.h"
#include "security.h"
#include "server.h"
#include "service.h"
#include "store.h"

using namespace glimpse::server;

namespace {

int Run(const ServerConfig& config, const sigset_t& signals) {
  const int cpus = ProcessCpus();
  // Each completion queue holds a thread polling it: a thread quota no larger leaves none to serve, and
  // every call would be RESOURCE_EXHAUSTED while health says SERVING.
  if (config.threads > 0 && config.threads <= CompletionQueues(cpus)) {
    std::fprintf(stderr, "glimpse-server: --threads %d leaves no thread to serve calls: gRPC's %d completion queues "
                         "hold one each (give at least %d, or 0 for the default)\n",
                 config.threads, CompletionQueues(cpus), CompletionQueues(cpus) + 1);
    return 2;
  }
  // Secrets first: a bad certificate or token file stops the server before it opens anything.
  auto credentials = LoadServerCredentials(config.tls);
  if (!credentials) {
    std::fprintf(stderr, "glimpse-server: %s\n", credentials.error().message.c_str());
    return 1;
  }
  std::string token = config.auth_token;
  if (!config.auth_token_file.empty()) {
    auto read = ReadTokenFile(config.auth_token_file);
    if (!read) {
      std::fprintf(stderr, "glimpse-server: %s\n", read.error().message.c_str());
      return 1;
    }
    token = std::move(*read);
  }
  auto store = ModelStore::Open(config.db_path);
  if (!store) {
    std::fprintf(stderr, "glimpse-server: cannot open the model store: %s\n", store.error().message.c_str());
    return 1;
  }
  Metrics metrics;
  std::unique_ptr<prometheus::Exposer> exposer;
  if (config.metrics_port > 0) {
    try {
      exposer = std::make_unique<prometheus::Exposer>("0.0.0.0:" + std::to_string(config.metrics_port));
      exposer->RegisterCollectable(metrics.registry());
    } catch (const std::exception& e) {
      std::fprintf(stderr,
                   "glimpse-server: cannot serve metrics on port %d (in use? --metrics-port 0 turns metrics off): %s\n",
                   config.metrics_port, e.what());
      return 1;
    }
  }

  ServiceOptions options;
  options.store = store->get();
  const int request_threads = RequestThreads(config, cpus);
  options.engine = CoreEngine(request_threads);
  options.limits = config.limits;
  options.metrics = &metrics;
  options.auth_token = token;
  GlimpseService service(std::move(options));

  GrpcServerOptions grpc_options;
  grpc_options.address = config.address;
  grpc_options.threads = EffectiveThreads(config, cpus);
  grpc_options.completion_queues = CompletionQueues(cpus);
  grpc_options.max_message_bytes = config.limits.max_message_bytes;
  grpc_options.credentials = *credentials;
  auto running = StartGrpcServer(grpc_options, &service);
  if (!running) {
    std::fprintf(stderr, "glimpse-server: %s\n", running.error().message.c_str());
    return 1;
  }
  LogEvent("info", "serving glimpse.v1.Glimpse on " + config.address + " (port " + std::to_string(running->port) +
                       "), store " + config.db_path + ", metrics port " + std::to_string(config.metrics_port) +
                       ", " + std::to_string(cpus) + " usable CPUs, " + std::to_string(grpc_options.threads) +
                       " gRPC threads, " + std::to_string(request_threads) + " threads per request, " +
                       (config.tls.enabled() ? (config.tls.client_ca.empty() ? "TLS" : "mutual TLS") : "plaintext") +
                       (token.empty() ? ", model changes open to every caller" : ", model changes need the bearer token"));

  int signal = 0;
  sigwait(&signals, &signal);
  LogEvent("info", std::string("received ") + (signal == SIGTERM ? "SIGTERM" : "SIGINT") + ", draining calls for up to " +
                       std::to_string(config.shutdown_grace.count()) + " s");
  ShutdownGrpcServer(*running->server, config.shutdown_grace);
  LogEvent("info", "stopped; closing the model store");
  return 0;  // service, then store, are destroyed here: the database is closed cleanly
}

}  // namespace

int main(int argc, char** argv) {
  // Block the stop signals in every thread (gRPC's and prometheus' inherit the mask); the main thread
  // waits for them with sigwait, so no code runs in a signal handler.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  auto config = ParseConfig(std::vector<std::string>(argv + 1, argv + argc), ProcessEnv());
  if (!config) {
    std::fprintf(stderr, "glimpse-server: %s\n", config.error().message.c_str());
    return 2;
  }
  if (config->help) {
    std::fputs(Usage().c_str(), stdout);
    return 0;
  }
  try {
    return Run(*config, signals);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "glimpse-server: fatal: %s\n", e.what());
    return 1;
  }
}

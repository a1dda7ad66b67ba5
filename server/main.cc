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

// --threads no larger than the completion queues: each queue holds a thread polling it, none would be left
// to serve, and every call would be RESOURCE_EXHAUSTED while health says SERVING.
bool ThreadsLeaveNoneToServe(const ServerConfig& config, int cpus) {
  if (config.threads <= 0 || config.threads > CompletionQueues(cpus)) return false;
  std::fprintf(stderr, "glimpse-server: --threads %d leaves no thread to serve calls: gRPC's %d completion queues "
                       "hold one each (give at least %d, or 0 for the default)\n",
               config.threads, CompletionQueues(cpus), CompletionQueues(cpus) + 1);
  return true;
}

// The token model changes need: --auth-token, or the one in --auth-token-file.
glimpse::Expected<std::string> AuthToken(const ServerConfig& config) {
  if (config.auth_token_file.empty()) return config.auth_token;
  return ReadTokenFile(config.auth_token_file);
}

// The metrics endpoint on 0.0.0.0:--metrics-port (none for port 0).
glimpse::Expected<std::unique_ptr<prometheus::Exposer>> ServeMetrics(const ServerConfig& config, Metrics& metrics) {
  if (config.metrics_port <= 0) return std::unique_ptr<prometheus::Exposer>();
  try {
    auto exposer = std::make_unique<prometheus::Exposer>("0.0.0.0:" + std::to_string(config.metrics_port));
    exposer->RegisterCollectable(metrics.registry());
    return exposer;
  } catch (const std::exception& e) {
    return glimpse::internal_error("cannot serve metrics on port " + std::to_string(config.metrics_port) +
                                   " (in use? --metrics-port 0 turns metrics off): " + e.what());
  }
}

std::string ServingLine(const ServerConfig& config, int port, int cpus, const GrpcServerOptions& grpc_options,
                        int request_threads, bool token) {
  return "serving glimpse.v1.Glimpse on " + config.address + " (port " + std::to_string(port) + "), store " +
         config.db_path + ", metrics port " + std::to_string(config.metrics_port) + ", " + std::to_string(cpus) +
         " usable CPUs, " + std::to_string(grpc_options.threads) + " gRPC threads, " +
         std::to_string(request_threads) + " threads per request, " +
         (config.tls.enabled() ? (config.tls.client_ca.empty() ? "TLS" : "mutual TLS") : "plaintext") +
         (token ? ", model changes need the bearer token" : ", model changes open to every caller");
}

int Fail(const std::string& message) {
  std::fprintf(stderr, "glimpse-server: %s\n", message.c_str());
  return 1;
}

int Run(const ServerConfig& config, const sigset_t& signals) {
  const int cpus = ProcessCpus();
  if (ThreadsLeaveNoneToServe(config, cpus)) return 2;
  // Secrets first: a bad certificate or token file stops the server before it opens anything.
  auto credentials = LoadServerCredentials(config.tls);
  if (!credentials) return Fail(credentials.error().message);
  auto token = AuthToken(config);
  if (!token) return Fail(token.error().message);
  auto store = ModelStore::Open(config.db_path);
  if (!store) return Fail("cannot open the model store: " + store.error().message);
  Metrics metrics;
  auto exposer = ServeMetrics(config, metrics);
  if (!exposer) return Fail(exposer.error().message);

  ServiceOptions options;
  options.store = store->get();
  const int request_threads = RequestThreads(config, cpus);
  options.engine = CoreEngine(request_threads);
  options.limits = config.limits;
  options.metrics = &metrics;
  options.auth_token = *token;
  GlimpseService service(std::move(options));

  GrpcServerOptions grpc_options;
  grpc_options.address = config.address;
  grpc_options.threads = EffectiveThreads(config, cpus);
  grpc_options.completion_queues = CompletionQueues(cpus);
  grpc_options.max_message_bytes = config.limits.max_message_bytes;
  grpc_options.credentials = *credentials;
  auto running = StartGrpcServer(grpc_options, &service);
  if (!running) return Fail(running.error().message);
  LogEvent("info", ServingLine(config, running->port, cpus, grpc_options, request_threads, !token->empty()));

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

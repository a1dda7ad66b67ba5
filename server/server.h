// Builds the gRPC server around a service: listen address, message and thread limits, the standard
// health service (SERVING for "" and glimpse.v1.Glimpse) and server reflection. Used by main.cc and
// by the end-to-end tests.
#pragma once

#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server.h>

#include <memory>
#include <string>

#include "glimpse/expected.h"
#include "limits.h"

namespace glimpse::server {

inline constexpr const char* kServiceName = "glimpse.v1.Glimpse";

struct GrpcServerOptions {
  std::string address = "0.0.0.0:50051";  // "127.0.0.1:0" picks a free port
  int threads = 16;  // at most this many threads serve calls (a sync call holds one while it runs)
  // Completion queues of the sync server, each with 1-2 polling threads; 0: gRPC's default, one per
  // core of the node (64 idle pollers in a 2-CPU container on a 64-core node).
  int completion_queues = 0;
  size_t max_message_bytes = 64u << 20;
  std::shared_ptr<grpc::ServerCredentials> credentials;  // LoadServerCredentials (security.h); null: plaintext
};

struct RunningServer {
  std::unique_ptr<grpc::Server> server;
  int port = 0;  // the port actually bound
};

Expected<RunningServer> StartGrpcServer(const GrpcServerOptions& options, grpc::Service* service);

// Health goes NOT_SERVING, new calls are refused, in-flight calls get until `grace` to finish and are
// then cancelled; returns once every handler has returned.
void ShutdownGrpcServer(grpc::Server& server, std::chrono::milliseconds grace);

}  // namespace glimpse::server

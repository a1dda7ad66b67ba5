#include "server.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/resource_quota.h>
#include <grpcpp/server_builder.h>

#include <climits>

namespace glimpse::server {

Expected<RunningServer> StartGrpcServer(const GrpcServerOptions& options, grpc::Service* service) {
  // Both are process-wide switches read when a builder is made; calling them again is harmless.
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();

  grpc::ServerBuilder builder;
  RunningServer running;
  // gRPC sets SO_REUSEPORT on Linux by default: a second server on a port already served would start
  // and take about half of the calls. A port in use is a startup error instead.
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  builder.AddListeningPort(options.address,
                           options.credentials ? options.credentials : grpc::InsecureServerCredentials(), &running.port);
  builder.RegisterService(service);
  const int max_bytes = static_cast<int>(std::min<size_t>(options.max_message_bytes, INT_MAX));
  builder.SetMaxReceiveMessageSize(max_bytes);
  builder.SetMaxSendMessageSize(max_bytes);
  // Each sync call holds a thread; beyond the quota new calls get RESOURCE_EXHAUSTED.
  grpc::ResourceQuota quota("glimpse-server");
  quota.SetMaxThreads(std::max(2, options.threads));
  builder.SetResourceQuota(quota);
  if (options.completion_queues > 0) {
    builder.SetSyncServerOption(grpc::ServerBuilder::SyncServerOption::NUM_CQS, options.completion_queues);
    builder.SetSyncServerOption(grpc::ServerBuilder::SyncServerOption::MIN_POLLERS, 1);
    builder.SetSyncServerOption(grpc::ServerBuilder::SyncServerOption::MAX_POLLERS, 2);
  }

  running.server = builder.BuildAndStart();
  if (!running.server || running.port == 0)
    return failed_precondition("cannot listen on " + options.address + " (address in use or invalid?)");
  grpc::HealthCheckServiceInterface* health = running.server->GetHealthCheckService();
  if (!health) return internal_error("the default health check service is missing");
  health->SetServingStatus("", true);
  health->SetServingStatus(kServiceName, true);
  return running;
}

void ShutdownGrpcServer(grpc::Server& server, std::chrono::milliseconds grace) {
  if (auto* health = server.GetHealthCheckService()) health->Shutdown();  // NOT_SERVING from now on
  server.Shutdown(std::chrono::system_clock::now() + grace);
  server.Wait();
}

}  // namespace glimpse::server

// glimpse health: the standard grpc.health.v1 Check.
#include <cstdio>

#include "client/commands.h"
#include "grpc/health/v1/health.grpc.pb.h"

namespace glimpse::client {

int RunHealth(const ConnectionOptions& conn, const std::string& service) {
  auto channel = MakeChannel(conn);
  if (!channel) {
    PrintError("health", channel.error().message);
    return kExitError;
  }
  auto stub = grpc::health::v1::Health::NewStub(*channel);
  grpc::ClientContext context;
  PrepareContext(context, conn, /*default_timeout_s=*/5);
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(service);
  grpc::health::v1::HealthCheckResponse response;
  const grpc::Status status = stub->Check(&context, request, &response);
  const std::string what = "health " + conn.server + (service.empty() ? "" : " " + service);
  if (!status.ok()) {
    PrintError(what, FormatStatus(status));
    return kExitError;
  }
  const std::string state = grpc::health::v1::HealthCheckResponse::ServingStatus_Name(response.status());
  std::printf("%s\n", state.c_str());
  return response.status() == grpc::health::v1::HealthCheckResponse::SERVING ? kExitOk : kExitError;
}

}  // namespace glimpse::client

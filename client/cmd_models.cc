// glimpse models list | show | delete | set-default: the model-management RPCs.
#include <cstdio>
#include <string>

#include "client/commands.h"
#include "client/parse.h"
#include "client/render.h"

namespace glimpse::client {
namespace {

constexpr double kTimeoutS = 30;

int Fail(const std::string& what, const grpc::Status& status) {
  PrintError(what, FormatStatus(status));
  return kExitError;
}

}  // namespace

int RunModelsList(const ConnectionOptions& conn, const std::string& name, bool json) {
  const std::string what = "models list" + (name.empty() ? "" : " " + name);
  auto stub = ConnectGlimpse(conn, what);
  if (!stub) return kExitError;
  grpc::ClientContext context;
  PrepareContext(context, conn, kTimeoutS);
  v1::ListModelsRequest request;
  request.set_name(name);
  v1::ListModelsResponse response;
  if (grpc::Status s = stub->ListModels(&context, request, &response); !s.ok()) return Fail(what, s);
  if (json) {
    for (const v1::ModelInfo& m : response.models()) PrintOut(ModelJson(m) + "\n");
  } else {
    PrintOut(ModelsTable(response));
  }
  return kExitOk;
}

int RunModelsShow(const ConnectionOptions& conn, const std::string& ref, bool json) {
  const std::string what = "models show " + ref;
  auto stub = ConnectGlimpse(conn, what);
  if (!stub) return kExitError;
  grpc::ClientContext context;
  PrepareContext(context, conn, kTimeoutS);
  v1::GetModelRequest request;
  *request.mutable_model() = *ParseModelRef(ref);
  v1::ModelInfo response;
  if (grpc::Status s = stub->GetModel(&context, request, &response); !s.ok()) return Fail(what, s);
  PrintOut(json ? ModelJson(response) + "\n" : ModelDetails(response));
  return kExitOk;
}

int RunModelsDelete(const ConnectionOptions& conn, const std::string& ref) {
  const std::string what = "models delete " + ref;
  auto stub = ConnectGlimpse(conn, what);
  if (!stub) return kExitError;
  grpc::ClientContext context;
  PrepareContext(context, conn, kTimeoutS);
  const v1::ModelRef model = *ParseModelRef(ref);
  v1::DeleteModelRequest request;
  request.set_name(model.name());
  request.set_version(model.version());
  v1::DeleteModelResponse response;
  if (grpc::Status s = stub->DeleteModel(&context, request, &response); !s.ok()) return Fail(what, s);
  std::string versions;
  for (uint32_t v : response.deleted_versions()) versions += (versions.empty() ? "" : ", ") + std::to_string(v);
  PrintOut("deleted " + model.name() + (response.deleted_versions_size() == 1 ? " version " : " versions ") +
        (versions.empty() ? "(none)" : versions) + "\n");
  return kExitOk;
}

int RunModelsSetDefault(const ConnectionOptions& conn, const std::string& ref) {
  const std::string what = "models set-default " + ref;
  auto stub = ConnectGlimpse(conn, what);
  if (!stub) return kExitError;
  grpc::ClientContext context;
  PrepareContext(context, conn, kTimeoutS);
  const v1::ModelRef model = *ParseModelRef(ref, /*allow_latest=*/true);
  v1::SetDefaultModelRequest request;
  request.set_name(model.name());
  request.set_version(model.version());
  v1::ModelInfo response;
  if (grpc::Status s = stub->SetDefaultModel(&context, request, &response); !s.ok()) return Fail(what, s);
  PrintOut(model.version() == 0 ? model.name() + ": no pinned version, serving the latest (" +
                                   std::to_string(response.version()) + ")\n"
                             : "default of " + model.name() + " is now version " + std::to_string(response.version()) +
                                   "\n");
  return kExitOk;
}

}  // namespace glimpse::client

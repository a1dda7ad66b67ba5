// glimpse classify: one Classify call per file; a score table (or JSON lines) on stdout.
#include "client/cloud_convert.h"
#include "client/commands.h"
#include "client/parse.h"
#include "client/render.h"

namespace glimpse::client {
namespace {

constexpr double kTimeoutS = 60;

// Errors about one cloud; any other (unknown model, server down, ...) would repeat for every file.
bool PerFile(grpc::StatusCode code) {
  return code == grpc::StatusCode::INVALID_ARGUMENT || code == grpc::StatusCode::RESOURCE_EXHAUSTED;
}

}  // namespace

int RunClassify(const ConnectionOptions& conn, const ClassifyOptions& o) {
  v1::ClassifyRequest request;
  if (!o.model.empty()) *request.mutable_model() = *ParseModelRef(o.model);
  if (!o.method.empty()) request.set_method(*ParseMethod(o.method));
  auto stub = ConnectGlimpse(conn, "classify");
  if (!stub) return kExitError;

  std::vector<ClassifyRow> rows;
  int exit_code = kExitOk;
  for (const std::string& file : o.files) {
    const std::string what = "classify " + file;
    auto cloud = CloudToClassify(file, o.views);
    if (!cloud) {
      PrintError("classify", cloud.error().message);  // core messages start with the path
      exit_code = kExitError;
      continue;
    }
    ToProto(*cloud, request.mutable_cloud());
    grpc::ClientContext context;
    PrepareContext(context, conn, kTimeoutS);
    ClassifyRow row{file, {}};
    if (grpc::Status s = stub->Classify(&context, request, &row.response); !s.ok()) {
      PrintError(what, FormatStatus(s));
      exit_code = kExitError;
      if (PerFile(s.error_code())) continue;
      break;
    }
    if (o.json) PrintOut(ClassifyJson(row) + "\n");
    rows.push_back(std::move(row));
  }
  if (!o.json && !rows.empty()) {
    const v1::ClassifyResponse& first = rows.front().response;
    PrintOut("model " + FormatModelRef(first.model()) + "  method " + MethodName(first.method()) + "\n" +
             ClassifyTable(rows));
  }
  return exit_code;
}

}  // namespace glimpse::client

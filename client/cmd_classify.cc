// glimpse classify: every file read (a cloud as it is, a mesh as one single view, as train makes
// them), sent in ClassifyBatch calls (one Classify for a single file, or for a server without
// ClassifyBatch), and one answer printed per file: a score table (errors and warnings on stderr) or a
// JSON object per file, errors included, in the same shape whether the file was missing or the server
// refused it.
#include <algorithm>

#include "client/batch_client.h"
#include "client/commands.h"
#include "client/parse.h"
#include "client/render.h"
#include "proto/wire/errors.h"
#include "proto/wire/methods.h"

namespace glimpse::client {
namespace {

constexpr double kTimeoutS = 60;  // per file

struct FileResult {
  std::string file;
  std::optional<Cloud> cloud;        // what is sent, once read
  std::optional<v1::ClassifyResponse> response;
  grpc::StatusCode code = grpc::StatusCode::OK;
  std::string message;

  void Fail(grpc::StatusCode c, std::string m) {
    code = c;
    // Core's messages start with the path; the file is named once.
    if (m.rfind(file + ": ", 0) == 0) m = m.substr(file.size() + 2);
    message = std::move(m);
  }
};

Expected<Cloud> ReadInput(const std::string& file, const ClassifyOptions& o) {
  auto loaded = LoadFile(file);
  if (!loaded) return loaded.error();
  if (Status s = ApplyCameraFov(*loaded, o.camera_fov, file); !s.ok()) return s.error();
  if (Status s = ApplySensor(*loaded, o.sensor, file); !s.ok()) return s.error();
  if (loaded->is_mesh)
    return MeshFileView(file, o.placement, o.protocol, o.whole ? std::nullopt : std::optional<int>(o.view));
  if (o.view_given)
    PrintError("classify " + file, "warning: --view and --whole are for meshes; a cloud file is sent as it is");
  RemoveNonFinite(loaded->cloud);
  if (Status s = PlaceCloud(loaded->cloud, o.placement, file); !s.ok()) return s.error();
  return std::move(loaded->cloud);
}

}  // namespace

int RunClassify(const ConnectionOptions& conn, const ClassifyOptions& o) {
  std::vector<FileResult> results(o.files.size());
  for (size_t i = 0; i < o.files.size(); ++i) {
    results[i].file = o.files[i];
    auto cloud = ReadInput(o.files[i], o);
    if (cloud) results[i].cloud = std::move(*cloud);
    else results[i].Fail(wire::ToGrpcCode(cloud.error().code), cloud.error().message);
  }
  std::vector<Cloud> clouds;
  std::vector<FileResult*> sent;
  for (FileResult& r : results)
    if (r.cloud) {
      clouds.push_back(std::move(*r.cloud));
      sent.push_back(&r);
    }
  if (!clouds.empty()) {
    auto stub = ConnectGlimpse(conn, "classify");
    if (!stub) return kExitError;
    BatchClassifier classifier(conn, *stub, *ParseModelRef(o.model),
                               o.method.empty() ? v1::METHOD_UNSPECIFIED : *wire::ParseMethod(o.method), kTimeoutS);
    classifier.set_known_acceptance(o.known_acceptance);
    BatchAnswers answers = classifier.Classify(clouds);
    for (size_t i = 0; i < sent.size(); ++i) {
      if (answers.answers[i].response) {
        sent[i]->response = std::move(answers.answers[i].response);
        continue;
      }
      // The server numbers the batch's clouds; the file is named instead.
      std::string message = std::move(answers.answers[i].message);
      if (const std::string place = "cloud " + std::to_string(i) + ": "; message.rfind(place, 0) == 0)
        message = message.substr(place.size());
      sent[i]->Fail(answers.answers[i].code, std::move(message));
    }
  }

  int exit_code = kExitOk;
  std::vector<ClassifyRow> rows;
  for (FileResult& r : results) {
    if (!r.response) {
      exit_code = kExitError;
      const char* code = wire::StatusCodeName(r.code);
      if (o.json) PrintOut(ClassifyErrorJson(r.file, code, r.message) + "\n");
      else PrintError("classify " + r.file, std::string(code) + ": " + r.message);
      continue;
    }
    ClassifyRow row{r.file, std::move(*r.response)};
    if (o.json) PrintOut(ClassifyJson(row) + "\n");
    else if (!row.response.warning().empty()) PrintError("classify " + r.file, "warning: " + row.response.warning());
    rows.push_back(std::move(row));
  }
  if (!o.json && !rows.empty()) {
    const v1::ClassifyResponse& first = rows.front().response;
    // What the category columns hold: calibrated probabilities, or scores for a model without them.
    const bool calibrated = first.scores_size() > 0 && first.scores(0).has_probability();
    PrintOut("model " + FormatModelRef(first.model()) + "  method " + wire::MethodName(first.method()) +
             (calibrated ? "  probabilities" : "  scores") + "\n" + ClassifyTable(rows));
  }
  return exit_code;
}

}  // namespace glimpse::client

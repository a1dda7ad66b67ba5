// glimpse evaluate: a labelled mesh folder against a stored model, through the service. Every object
// is loaded and viewed exactly as glimpse-lab does (client/objects.h), each view cut at the stages
// asked for, and the clouds classified in ClassifyBatch calls while the next objects are prepared;
// then accuracy, balanced accuracy, the confusion table and the misclassified objects.
#include <chrono>
#include <cstdio>
#include <future>
#include <map>

#include "client/batch_client.h"
#include "client/commands.h"
#include "client/evaluate.h"
#include "client/parse.h"
#include "client/render.h"
#include "proto/wire/errors.h"
#include "proto/wire/methods.h"

namespace glimpse::client {
namespace {

constexpr double kTimeoutPerCloudS = 30;

struct Item {
  int object = 0, view = 0;
  size_t stage = 0;
};

// The clouds of objects [begin, end): every view at every stage, or the object's failure.
struct Prepared {
  std::vector<Cloud> clouds;
  std::vector<Item> items;
  std::vector<size_t> full_points;  // per item
  std::vector<EvaluationReport::Failure> failures;
};

Prepared Prepare(const Folder& folder, const std::vector<DatasetObject>& objects, size_t begin, size_t end,
                 const EvaluateOptions& o, const std::vector<Stage>& stages) {
  Prepared p;
  for (size_t i = begin; i < end; ++i) {
    auto views = ProtocolViews(objects[i], folder.sizing, o.protocol);
    if (!views) {
      p.failures.push_back({int(i), -1, "", wire::StatusCodeName(wire::ToGrpcCode(views.error().code)), views.error().message});
      continue;
    }
    for (size_t v = 0; v < views->views.size(); ++v)
      for (size_t s = 0; s < stages.size(); ++s) {
        p.clouds.push_back(StageCloud(views->views[v], views->full.size(), stages[s]));
        p.items.push_back({int(i), int(v), s});
        p.full_points.push_back(views->full.size());
      }
  }
  return p;
}

// Objects done on stderr: a bar redrawn on a terminal, else a line per 10 %.
class Progress {
 public:
  Progress(size_t total, bool quiet) : total_(total), quiet_(quiet), tty_(IsTerminal(stderr)) {}
  void Show(size_t done) {
    if (quiet_ || total_ == 0) return;
    const double f = double(done) / double(total_);
    if (tty_) {
      std::fprintf(stderr, "\r[%s] %3d%%  objects %zu/%zu\x1b[K", Bar(f, 30).c_str(), int(100 * f), done, total_);
    } else if (int decile = int(10 * f); decile > decile_) {
      decile_ = decile;
      std::fprintf(stderr, "evaluate: %d%% (%zu/%zu objects)\n", 10 * decile, done, total_);
    }
    std::fflush(stderr);
  }
  void End() {
    if (!quiet_ && tty_) std::fputc('\n', stderr);
  }

 private:
  size_t total_;
  bool quiet_, tty_;
  int decile_ = -1;
};

// The objects evaluated: every one, or the first max_per_category of each category.
std::vector<DatasetObject> Chosen(const Dataset& d, size_t max_per_category) {
  std::vector<DatasetObject> out;
  std::map<std::string, size_t> taken;
  for (const DatasetObject& o : d.objects)
    if (max_per_category == 0 || taken[o.category]++ < max_per_category) out.push_back(o);
  return out;
}

StageDecision Decision(const EvaluationReport& r, const Item& item, size_t full_points, const Cloud& cloud,
                       const CloudAnswer& answer) {
  StageDecision d;
  d.object = item.object;
  d.view = item.view;
  d.stage = stage_name(r.stages[item.stage]);
  d.method = r.method_id;
  d.truth = r.object_truth[static_cast<size_t>(item.object)];
  d.points = cloud.points.size();
  d.visible_fraction = double(d.points) / double(std::max<size_t>(1, full_points));
  if (!answer.response) return d;
  const v1::ClassifyResponse& resp = *answer.response;
  d.keypoints = resp.keypoints();
  d.winner = resp.winner_index();  // the report's categories start with the model's, in its order
  d.scores.assign(r.categories.size(), 0.0);
  for (int c = 0; c < resp.scores_size() && size_t(c) < d.scores.size(); ++c) d.scores[size_t(c)] = resp.scores(c).score();
  if (resp.scores_size() > 0 && resp.scores(0).has_probability())
    for (const v1::CategoryScore& s : resp.scores()) d.probabilities.push_back(s.probability());
  return d;
}

// The model once, by name: its categories, and the version pinned for every call of the run.
grpc::Status GetModel(v1::Glimpse::Stub& stub, const ConnectionOptions& conn, const std::string& model,
                      v1::ModelInfo* info) {
  grpc::ClientContext context;
  PrepareContext(context, conn, 30);
  v1::GetModelRequest request;
  *request.mutable_model() = *ParseModelRef(model);
  return stub.GetModel(&context, request, info);
}

// The report before any answer: what is evaluated, against which model, method and categories.
EvaluationReport NewReport(const EvaluateOptions& o, const Folder& folder, const std::vector<DatasetObject>& objects,
                           const v1::ModelInfo& info, v1::Method method, const std::vector<Stage>& stages) {
  EvaluationReport report;
  report.folder = o.dir;
  report.model = info.name() + ":" + std::to_string(info.version());
  report.method = wire::MethodName(method);
  const auto method_id = wire::MethodFromProto(method);
  report.method_id = method_id.ok() && *method_id ? **method_id : MethodId::kFusion;
  report.categories = ReportCategories({info.categories().begin(), info.categories().end()}, folder.dataset.categories);
  report.model_categories = static_cast<size_t>(info.categories_size());
  report.stages = stages;
  report.views_per_object = std::max<size_t>(1, o.protocol.views);
  for (const DatasetObject& obj : objects) {
    report.objects.push_back(ObjectKey(obj));
    report.object_truth.push_back(int(std::find(report.categories.begin(), report.categories.end(), obj.category) -
                                      report.categories.begin()));
  }
  return report;
}

void PrintApplied(const Folder& folder) {
  for (const std::string& line : folder.applied)
    if (line.find(" cloud files: ") == std::string::npos) std::fprintf(stderr, "evaluate: %s\n", line.c_str());
  // A cloud file has no object to view at every stage: evaluate judges the meshes only.
  if (!folder.clouds.empty())
    std::fprintf(stderr, "evaluate: %zu cloud files not evaluated (a cloud is one view of an unknown object; "
                         "glimpse classify decides them)\n", folder.clouds.size());
}

// The answers of one step's clouds, and every view and stage of an object that did not load (all wrong).
void AddAnswers(const Prepared& step, const BatchAnswers& answers, EvaluationReport& report) {
  for (size_t i = 0; i < step.items.size(); ++i) {
    const CloudAnswer& a = answers.answers[i];
    report.decisions.push_back(Decision(report, step.items[i], step.full_points[i], step.clouds[i], a));
    if (!a.response)
      report.failures.push_back({step.items[i].object, step.items[i].view,
                                 stage_name(report.stages[step.items[i].stage]), wire::StatusCodeName(a.code),
                                 a.message});
  }
  for (const EvaluationReport::Failure& f : step.failures) {
    report.failures.push_back(f);
    for (size_t v = 0; v < report.views_per_object; ++v)
      for (size_t s = 0; s < report.stages.size(); ++s) {
        const Item item{f.object, int(v), s};
        report.decisions.push_back(Decision(report, item, 0, Cloud{}, CloudAnswer{}));
      }
  }
}

// Every object's clouds classified in steps of whole objects; the next step is read and viewed while the
// server classifies the current one. The status of a call that failed as a whole (the model, the server).
grpc::Status ClassifyAll(BatchClassifier& classifier, const Folder& folder, const std::vector<DatasetObject>& objects,
                         const EvaluateOptions& o, EvaluationReport& report) {
  const size_t per_object = report.views_per_object * report.stages.size();
  const size_t step = std::max<size_t>(1, o.batch_clouds / per_object);
  Progress progress(objects.size(), o.quiet);
  progress.Show(0);
  const auto prepare = [&](size_t begin) {
    return std::async(std::launch::async, Prepare, std::cref(folder), std::cref(objects), begin,
                      std::min(begin + step, objects.size()), std::cref(o), std::cref(report.stages));
  };
  auto next = prepare(0);
  for (size_t begin = 0; begin < objects.size(); begin += step) {
    Prepared current = next.get();
    const size_t after = begin + step;
    if (after < objects.size()) next = prepare(after);
    const BatchAnswers answers = classifier.Classify(current.clouds);
    if (!answers.call.ok()) {  // about every cloud: no use going on
      progress.End();
      if (next.valid()) next.wait();
      return answers.call;
    }
    AddAnswers(current, answers, report);
    progress.Show(std::min(after, objects.size()));
  }
  progress.End();
  return grpc::Status::OK;
}

}  // namespace

int RunEvaluate(const ConnectionOptions& conn, const EvaluateOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string what = "evaluate " + o.dir;
  auto stages = ParseStages(o.stages);
  if (!stages) {
    PrintError(what, stages.error().message);
    return kExitUsage;
  }
  auto folder = ScanFolder(o.dir, o.placement);
  if (!folder) {
    PrintError(what, folder.error().message);
    return kExitError;
  }
  const std::vector<DatasetObject> objects = Chosen(folder->dataset, o.max_per_category);
  if (objects.empty()) {
    PrintError(what, "no meshes to evaluate (cloud files cannot be viewed as the protocol views objects)");
    return kExitError;
  }
  auto stub = ConnectGlimpse(conn, what);
  if (!stub) return kExitError;
  v1::ModelInfo info;
  if (grpc::Status s = GetModel(*stub, conn, o.model, &info); !s.ok()) {
    PrintError(what, FormatStatus(s));
    return kExitError;
  }
  const v1::Method method = o.method.empty() ? info.default_method() : *wire::ParseMethod(o.method);
  EvaluationReport report = NewReport(o, *folder, objects, info, method, *stages);
  if (!o.quiet) PrintApplied(*folder);

  v1::ModelRef pinned;
  pinned.set_name(info.name());
  pinned.set_version(info.version());
  BatchClassifier classifier(conn, *stub, pinned, method, kTimeoutPerCloudS, {o.batch_clouds, 1'000'000});
  if (grpc::Status s = ClassifyAll(classifier, *folder, objects, o, report); !s.ok()) {
    PrintError(what, FormatStatus(s));
    return kExitError;
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  PrintOut(o.json ? EvaluationJson(report) + "\n" : EvaluationText(report));
  return kExitOk;
}

}  // namespace glimpse::client

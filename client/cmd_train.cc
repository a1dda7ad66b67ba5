// glimpse train: labelled clouds (from DIR or the procedural zoo) streamed over Train, with the
// server's progress shown on stderr, and the stored model printed at the end.
#include <cstdio>
#include <functional>
#include <set>
#include <utility>
#include <thread>

#include "client/commands.h"
#include "client/objects.h"
#include "client/parse.h"
#include "client/render.h"
#include "glimpse/learning/object_views.h"
#include "glimpse/geometry/scan_filters.h"
#include "glimpse/views/zoo.h"
#include "proto/wire/clouds.h"

namespace glimpse::client {
namespace {

constexpr double kTimeoutS = 3600;  // training a large set takes a while

// Calls emit(category, object_id, cloud, augmented) for every training cloud; stops at the first error
// or when emit returns false.
using Emit = std::function<bool(const std::string&, const std::string&, const Cloud&, bool)>;

// Emits the non-empty views (a view of nothing teaches nothing, and core refuses it); augmented: all of
// them, else the simulated sensors' (ObjectViews::first_augmented on).
bool EmitViews(const std::string& category, const std::string& object_id, const ObjectViews& views, const Emit& emit,
               bool augmented = false) {
  for (size_t v = 0; v < views.views.size(); ++v)
    if (!views.views[v].points.empty() &&
        !emit(category, object_id, views.views[v], augmented || v >= views.first_augmented))
      return false;
  return true;
}

// Every mesh of the folder as glimpse-lab loads and views it.
Status EmitMeshes(const ViewRecipe& recipe, double sensor_density, const Folder& folder, const Emit& emit) {
  const std::vector<DatasetObject>& objects = folder.dataset.objects;
  Status failed;
  ViewsInOrder(
      objects.size(), [&](size_t i) { return ProtocolViews(objects[i], folder.sizing, recipe, sensor_density); },
      [&](size_t i, Expected<ObjectViews>&& views) {
        if (!views) {
          failed = views.error();
          return false;
        }
        return EmitViews(objects[i].category, ObjectKey(objects[i]), *views, emit);
      });
  return failed;
}

// The folder's cloud files, as they are or as --unit / --up place them.
Status EmitCloudFiles(const Folder& folder, const Emit& emit) {
  for (const TrainFile& f : folder.clouds) {
    auto clouds = TrainingClouds(f.path, ViewOptions{});
    if (!clouds) return clouds.error();
    for (Cloud& c : *clouds) {
      if (Status s = PlaceCloud(c, folder.cloud_placement, f.path); !s.ok()) return s;
      if (!emit(f.category, f.object_id, c, false)) return {};
    }
  }
  return {};
}

// The procedural zoo's objects (upright, real-life size), viewed as glimpse-lab views them; only
// those of `categories` when given (a folder's, which the zoo adds to: then they are augmented, learnt
// but not what "unknown" measures against, as glimpse-lab's --also-train zoo:N).
Status EmitZoo(const TrainOptions& o, const ViewRecipe& recipe, double sensor_density,
               const std::set<std::string>& categories, const Emit& emit) {
  std::vector<LabelledMesh> zoo = make_zoo(o.per_category, recipe.seed);
  std::erase_if(zoo, [&](const LabelledMesh& z) { return !categories.empty() && !categories.count(z.category); });
  auto key = [&](size_t i) { return zoo[i].category + "/" + zoo[i].id; };
  ViewsInOrder(
      zoo.size(),
      [&](size_t i) -> Expected<ObjectViews> {
        return training_views(zoo[i].mesh, key(i), zoo[i].any_pose, recipe, sensor_density);
      },
      [&](size_t i, Expected<ObjectViews>&& views) {
        // "zoo/category/id": never the name of a folder's object (a folder's "human/1" is another object).
        return EmitViews(zoo[i].category, "zoo/" + key(i), *views, emit, !categories.empty());
      });
  return {};
}

// The first pass when simulated sensors are asked: every mesh's ideal views (the folder's and the
// zoo's, as they will be sent) give the density the model will classify at, which the sensors' views
// are thinned to (glimpse-lab: EvalResult::trained_density). Returns it and how many views it is of.
Expected<std::pair<double, size_t>> SensorDensity(const TrainOptions& o, const Folder& folder,
                                                  const std::set<std::string>& zoo_categories) {
  ViewRecipe ideal = o.protocol;
  ideal.train_sensors.clear();
  std::vector<double> density;
  const Emit measure = [&](const std::string&, const std::string&, const Cloud& cloud, bool) {
    density.push_back(relative_density(cloud.points));
    return true;
  };
  if (!o.dir.empty())
    if (Status s = EmitMeshes(ideal, 0, folder, measure); !s.ok()) return s.error();
  if (o.zoo)
    if (Status s = EmitZoo(o, ideal, 0, zoo_categories, measure); !s.ok()) return s.error();
  const size_t views = density.size();
  return std::pair{median_density(std::move(density)), views};
}

// Shows v1::TrainProgress on stderr: a bar redrawn in place on a terminal, else a line per stage and
// per 10 %.
class ProgressView {
 public:
  explicit ProgressView(bool quiet) : quiet_(quiet), tty_(IsTerminal(stderr)) {}
  void Show(const v1::TrainProgress& p) {
    if (quiet_) return;
    if (tty_) {
      std::fprintf(stderr, "\r%s\x1b[K", ProgressBar(p).c_str());
      drawn_ = true;
    } else if (p.stage() != stage_ || static_cast<int>(p.percent() / 10) != decile_ || p.has_model()) {
      std::fprintf(stderr, "%s\n", ProgressLine(p).c_str());
    }
    std::fflush(stderr);
    stage_ = p.stage();
    decile_ = static_cast<int>(p.percent() / 10);
  }
  void End() {
    if (drawn_) std::fputc('\n', stderr);
    drawn_ = false;
  }

 private:
  bool quiet_, tty_, drawn_ = false;
  std::string stage_;
  int decile_ = -1;
};

// With DIR, --zoo adds objects of the folder's categories only: those, and a line saying so.
Expected<std::set<std::string>> ZooCategoriesOf(const TrainOptions& o, Folder& folder) {
  std::set<std::string> in_folder(folder.dataset.categories.begin(), folder.dataset.categories.end());
  for (const TrainFile& f : folder.clouds) in_folder.insert(f.category);
  std::set<std::string> extra;
  std::string names;
  for (const std::string& c : zoo_categories())
    if (in_folder.count(c)) {
      extra.insert(c);
      names += (names.empty() ? "" : ", ") + c;
    }
  if (extra.empty())
    return invalid_argument("--zoo adds objects of the folder's categories, and the zoo has none of them (it has " +
                            Joined(zoo_categories(), ", ") + ")");
  folder.applied.push_back("also the procedural zoo: " + std::to_string(o.per_category) +
                           " objects per category of " + names + ", upright, real-life size");
  return extra;
}

// What is sent, on stderr: the folder's manifest and the zoo, then the views of meshes (the folder's or
// the zoo's: a folder of cloud files alone says nothing of them).
void PrintRecipe(const TrainOptions& o, const Folder& folder, bool meshes) {
  for (const std::string& line : folder.applied) std::fprintf(stderr, "train: %s\n", line.c_str());
  if (!meshes) return;
  const std::string views = o.protocol.views ? std::to_string(o.protocol.views) +
                                                   " views per mesh (hidden point removal from the paper's viewpoints), " +
                                                   std::to_string(o.protocol.points) + " surface samples, seed " +
                                                   std::to_string(o.protocol.seed)
                                             : "whole sampled clouds, no views";
  std::fprintf(stderr, "train: %s\n", views.c_str());
}

// What the simulated sensors' views are thinned to: 0 without sensors (or views, or meshes).
Expected<double> MeasureSensorDensity(const TrainOptions& o, const Folder& folder,
                                      const std::set<std::string>& zoo_extra, bool meshes) {
  const ViewRecipe& protocol = o.protocol;
  if (!meshes || !protocol.views || protocol.train_sensors.empty()) return 0.0;
  if (!o.quiet) std::fprintf(stderr, "train: measuring every mesh's ideal views' density (a first pass) ...\n");
  auto density = SensorDensity(o, folder, zoo_extra);
  if (!density) return density.error();
  if (!o.quiet) {
    const std::string sensors = describe(protocol.train_sensors);
    std::fprintf(stderr,
                 "train: and the same azimuths seen by a simulated %s, filtered to the ideal views' density (%.1f "
                 "points per extent^2, the median over %zu views; --sensor-views none: not)\n",
                 sensors.c_str(), density->first, density->second);
  }
  return density->first;
}

// The header: a new model's methods and parameters (with the views' density, kept so the model can grow
// alike), or the base a model grows from (its own).
v1::TrainRequest HeaderMessage(const TrainOptions& o, const std::vector<v1::Method>& methods, double view_density) {
  v1::TrainRequest header;
  v1::TrainHeader* h = header.mutable_header();
  h->set_model_name(o.name.empty() ? ParseModelRef(o.base)->name() : o.name);
  h->set_description(o.description);
  if (!o.base.empty()) {
    *h->mutable_base() = *ParseModelRef(o.base);
    return header;
  }
  for (v1::Method m : methods) h->add_methods(m);
  if (o.train_seed) h->mutable_parameters()->set_seed(*o.train_seed);
  if (o.no_scan_filters) h->mutable_parameters()->set_filter_scans(false);
  if (view_density > 0) h->mutable_parameters()->set_view_density(view_density);
  return header;
}

// The base version a model grows from (--base), as the server describes it.
Expected<v1::ModelInfo> BaseModel(v1::Glimpse::Stub& stub, const ConnectionOptions& conn, const std::string& ref) {
  grpc::ClientContext context;
  PrepareContext(context, conn, 30);
  v1::GetModelRequest request;
  *request.mutable_model() = *ParseModelRef(ref);
  v1::ModelInfo info;
  if (grpc::Status s = stub.GetModel(&context, request, &info); !s.ok())
    return failed_precondition("--base " + ref + ": " + FormatStatus(s));
  if (info.training_set_bytes() == 0)
    return failed_precondition("--base " + ref + ": the model keeps no training set, so it cannot grow; train it "
                               "again with its clouds and the added ones");
  return info;
}

// The density the simulated sensors' views are thinned to: the base's when the model grows (its views
// and the added ones alike), else measured in a first pass (0: no sensor views).
Expected<double> ViewDensity(v1::Glimpse::Stub& stub, const ConnectionOptions& conn, const TrainOptions& o,
                             const Folder& folder, const std::set<std::string>& zoo_extra, bool meshes) {
  if (o.base.empty()) return MeasureSensorDensity(o, folder, zoo_extra, meshes);
  auto base = BaseModel(stub, conn, o.base);
  if (!base) return base.error();
  const double density = base->parameters().view_density();
  if (density > 0 && meshes && o.protocol.views && !o.protocol.train_sensors.empty()) {
    if (!o.quiet)
      std::fprintf(stderr, "train: growing %s:%u; sensor views thinned to its views' density (%.1f points per extent^2)\n",
                   base->name().c_str(), base->version(), density);
    return density;
  }
  if (!o.quiet) std::fprintf(stderr, "train: growing %s:%u\n", base->name().c_str(), base->version());
  return MeasureSensorDensity(o, folder, zoo_extra, meshes);
}

struct TrainCall {
  Status loaded;        // reading and viewing the files
  grpc::Status status;  // the call's
  v1::ModelInfo model;  // the stored model, when the server reported one
};

// The Train call: the header, then every cloud (the folder's meshes, its cloud files, the zoo's objects)
// while the server's progress is read and shown.
TrainCall SendTraining(v1::Glimpse::Stub& stub, const ConnectionOptions& conn, const TrainOptions& o,
                       const v1::TrainRequest& header, const Folder& folder, const std::set<std::string>& zoo_extra,
                       double sensor_density) {
  grpc::ClientContext context;
  PrepareContext(context, conn, kTimeoutS);
  auto stream = stub.Train(&context);
  // Progress is read while clouds are still being written: the server reports as it receives,
  // and an unread stream would eventually stall both sides.
  ProgressView view(o.quiet);
  TrainCall call;
  std::thread reader([&] {
    v1::TrainProgress p;
    while (stream->Read(&p)) {
      view.Show(p);
      if (p.has_model()) call.model = p.model();
    }
  });
  bool open = stream->Write(header);
  v1::TrainRequest request;
  const Emit emit = [&](const std::string& category, const std::string& object_id, const Cloud& cloud, bool augmented) {
    if (!open) return false;
    v1::LabelledCloud* lc = request.mutable_cloud();
    lc->set_category(category);
    lc->set_object_id(object_id);
    lc->set_augmented(augmented);
    wire::CloudToProto(cloud, lc->mutable_cloud());
    open = stream->Write(request);
    return open;
  };
  Status& loaded = call.loaded;
  if (open && !o.dir.empty()) loaded = EmitMeshes(o.protocol, sensor_density, folder, emit);
  if (open && loaded.ok() && !o.dir.empty()) loaded = EmitCloudFiles(folder, emit);
  if (open && loaded.ok() && o.zoo) loaded = EmitZoo(o, o.protocol, sensor_density, zoo_extra, emit);
  if (!loaded.ok()) context.TryCancel();  // a failed call stores nothing
  if (open && loaded.ok()) stream->WritesDone();
  reader.join();
  call.status = stream->Finish();
  view.End();
  return call;
}

}  // namespace

int RunTrain(const ConnectionOptions& conn, const TrainOptions& o) {
  const std::string what = "train " + (o.dir.empty() ? std::string("--zoo") : o.dir);
  auto methods = ParseMethodList(o.methods);
  if (!methods) {
    PrintError(what, methods.error().message);
    return kExitUsage;
  }
  if (o.name.empty() && o.base.empty()) {
    PrintError(what, "--name is required (with --base, the base's name is the default)");
    return kExitUsage;
  }
  // The folder's listing and manifest first: a bad manifest row fails before anything is sent.
  Folder folder;
  std::set<std::string> zoo_extra;  // with a folder: the zoo adds objects of its categories only
  if (!o.dir.empty()) {
    auto scanned = ScanFolder(o.dir, o.placement);
    if (!scanned) {
      PrintError(what, scanned.error().message);
      return kExitError;
    }
    folder = std::move(*scanned);
    auto extra = o.zoo ? ZooCategoriesOf(o, folder) : std::set<std::string>();
    if (!extra) {
      PrintError(what, extra.error().message);
      return kExitUsage;
    }
    zoo_extra = std::move(*extra);
  } else {
    folder.applied = {"the procedural zoo: " + std::to_string(o.per_category) + " objects per category, upright, real-life size"};
  }
  const bool meshes = o.zoo || !folder.dataset.objects.empty();
  if (!o.quiet) PrintRecipe(o, folder, meshes);
  auto stub = ConnectGlimpse(conn, what);
  if (!stub) return kExitError;
  auto sensor_density = ViewDensity(*stub, conn, o, folder, zoo_extra, meshes);
  if (!sensor_density) {
    PrintError(what, sensor_density.error().message);
    return kExitError;
  }
  const TrainCall call = SendTraining(*stub, conn, o, HeaderMessage(o, *methods, *sensor_density), folder, zoo_extra,
                                      *sensor_density);
  if (!call.loaded.ok()) {
    PrintError(what, call.loaded.error().message);
    return kExitError;
  }
  if (!call.status.ok()) {
    PrintError(what, FormatStatus(call.status));
    return kExitError;
  }
  if (call.model.name().empty()) {
    PrintError(what, "the server ended training without reporting a stored model");
    return kExitError;
  }
  PrintOut((o.json ? ModelJson(call.model) : TrainSummary(call.model)) + "\n");
  return kExitOk;
}

}  // namespace glimpse::client

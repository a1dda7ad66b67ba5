// glimpse: the command-line client of the glimpse.v1.Glimpse service. This file only parses the
// command line (CLI11) and hands over to commands.h. Exit codes: 0 ok, 1 error, 2 usage.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <functional>

#include "client/commands.h"
#include "client/parse.h"
#include "client/scan.h"
#include "glimpse/zoo.h"

using namespace glimpse::client;

namespace {

// CLI11 check: empty string when valid, else the reason.
template <class Parse>
CLI::Validator Checked(Parse parse, const std::string& description) {
  return CLI::Validator(
      [parse](std::string& text) -> std::string {
        auto parsed = parse(text);
        return parsed ? std::string() : parsed.error().message;
      },
      description);
}

const CLI::Validator kModelRef = Checked(ParseModelRef, "NAME[:VERSION]");
const CLI::Validator kMethod = Checked(ParseMethod, "METHOD");
const CLI::Validator kMethodList = Checked(ParseMethodList, "M1,M2,..");
const CLI::Validator kOrder = Checked(ParseRevealOrder, "top-down|random|sweep");

void AddConnectionOptions(CLI::App& app, ConnectionOptions& conn) {
  app.add_option("--server", conn.server, "server address host:port")->envname("GLIMPSE_SERVER")
      ->capture_default_str()->group("Connection");
  app.add_option_function<double>("--timeout", [&conn](const double& s) { conn.timeout_s = s; },
                                  "deadline of every call in seconds [health 5, models 30, classify 60 per file, "
                                  "stream 120 + scan time, train 3600]")
      ->check(CLI::PositiveNumber)->group("Connection");
  auto* tls = app.add_flag("--tls", conn.tls, "connect with TLS")->group("Connection");
  auto* ca = app.add_option("--ca", conn.ca_file, "PEM CA certificate(s) to trust (default: system roots)")
                 ->check(CLI::ExistingFile)->group("Connection");
  auto* cert = app.add_option("--cert", conn.cert_file, "PEM client certificate for mutual TLS (with --key)")
                   ->check(CLI::ExistingFile)->group("Connection");
  auto* key = app.add_option("--key", conn.key_file, "PEM private key of --cert")
                  ->check(CLI::ExistingFile)->group("Connection");
  ca->needs(tls);
  cert->needs(tls)->needs(key);
  key->needs(tls)->needs(cert);
  app.add_option("--token", conn.token, "bearer token sent as 'authorization: Bearer <token>'")
      ->envname("GLIMPSE_TOKEN")->group("Connection");
}

void AddMeshOptions(CLI::App& cmd, ViewOptions& views) {
  cmd.add_option("--mesh-points", views.mesh_points, "points sampled on a mesh's surface")
      ->capture_default_str()->check(CLI::Range(size_t{100}, size_t{5'000'000}));
}

int Main(int argc, char** argv) {
  CLI::App app{"glimpse: recognise an object's category from a partial point cloud, with a Glimpse server.\n"
               "Exit status: 0 ok, 1 error, 2 usage.",
               "glimpse"};
  app.set_version_flag("--version", "glimpse 0.1.0");
  app.require_subcommand(1);
  app.fallthrough();  // connection options may also follow the subcommand
  ConnectionOptions conn;
  AddConnectionOptions(app, conn);
  std::function<int()> run;

  // health
  auto* health = app.add_subcommand("health", "check the server's health (exit 0 when SERVING)");
  std::string health_service;
  health->add_option("--service", health_service, "service to check (default: the whole server)");
  health->callback([&] { run = [&] { return RunHealth(conn, health_service); }; });

  // models
  auto* models = app.add_subcommand("models", "list, show, delete models, and choose the default version");
  models->require_subcommand(1);
  auto* list = models->add_subcommand("list", "list every model version (or one name's)");
  std::string list_name;
  bool list_json = false;
  list->add_option("NAME", list_name, "only this name's versions");
  list->add_flag("--json", list_json, "one JSON object per line");
  list->callback([&] { run = [&] { return RunModelsList(conn, list_name, list_json); }; });
  auto* show = models->add_subcommand("show", "details of one model (NAME: its default version)");
  std::string show_ref;
  bool show_json = false;
  show->add_option("MODEL", show_ref, "NAME[:VERSION]")->required()->check(kModelRef);
  show->add_flag("--json", show_json, "as JSON");
  show->callback([&] { run = [&] { return RunModelsShow(conn, show_ref, show_json); }; });
  auto* del = models->add_subcommand("delete", "delete a version (NAME:VERSION) or every version (NAME)");
  std::string delete_ref;
  del->add_option("MODEL", delete_ref, "NAME[:VERSION]")->required()->check(kModelRef);
  del->callback([&] { run = [&] { return RunModelsDelete(conn, delete_ref); }; });
  auto* set_default = models->add_subcommand("set-default", "serve NAME:VERSION when NAME is asked for "
                                                            "(NAME:latest: serve the newest)");
  std::string default_ref;
  set_default->add_option("MODEL", default_ref, "NAME:VERSION")->required()->check(kModelRef);
  set_default->callback([&] { run = [&] { return RunModelsSetDefault(conn, default_ref); }; });

  // train
  auto* train = app.add_subcommand("train", "train a new model version from DIR/<category>/<files> or the shape zoo");
  TrainOptions t;
  auto* dir = train->add_option("DIR", t.dir, "folder of category folders of .pcd .ply .xyz .off .obj files")
                  ->check(CLI::ExistingDirectory);
  auto* zoo = train->add_flag("--zoo", t.zoo, "train on the core's procedural shape zoo (" +
                                                   std::to_string(glimpse::zoo_categories().size()) + " categories)");
  dir->excludes(zoo);
  train->add_option("--per-category", t.per_category, "zoo objects per category")->capture_default_str()
      ->check(CLI::Range(size_t{1}, size_t{10000}));
  train->add_option("--seed", t.seed, "zoo shapes and surface sampling seed")->capture_default_str();
  train->add_option("--name", t.name, "model name ([A-Za-z0-9._-], 1-128)")->required()
      ->check(Checked([](const std::string& s) { return ParseModelRef(s + ":latest"); }, "NAME"));
  train->add_option("--methods", t.methods, "comma-separated: bok,bog,kgh,vfh,esf,ush,size,fusion (default: the server's)")
      ->check(kMethodList);
  train->add_option("--description", t.description, "free text stored with the model");
  train->add_option("--views", t.views.views, "single views (HPR) per mesh or zoo shape, 0 = the whole cloud")
      ->capture_default_str()->check(CLI::Range(0, 6));
  AddMeshOptions(*train, t.views);
  train->add_option_function<uint64_t>("--train-seed", [&t](const uint64_t& s) { t.train_seed = s; },
                                       "k-means and sampling seed of training (default: the server's)");
  train->add_flag("--json", t.json, "print the stored model as JSON");
  train->add_flag("-q,--quiet", t.quiet, "no progress on stderr");
  train->callback([&] { run = [&] { return RunTrain(conn, t); }; });

  // classify
  auto* classify = app.add_subcommand("classify", "classify point-cloud or mesh files");
  ClassifyOptions c;
  classify->add_option("FILE", c.files, "clouds (.pcd .ply .xyz) or meshes (.off .obj .ply)")->required();
  classify->add_option("--model", c.model, "NAME[:VERSION]")->envname("GLIMPSE_MODEL")->required()->check(kModelRef);
  classify->add_option("--method", c.method, "bok|bog|kgh|vfh|esf|ush|fusion (default: the model's)")->check(kMethod);
  classify->add_flag("--json", c.json, "one JSON object per file instead of a table");
  AddMeshOptions(*classify, c.views);
  classify->callback([&] { run = [&] { return RunClassify(conn, c); }; });

  // stream
  auto* stream = app.add_subcommand("stream", "simulate a scanner: reveal one view in chunks over StreamClassify");
  StreamOptions s;
  auto* file = stream->add_option("FILE", s.file, "cloud or mesh file");
  auto* zoo_shape = stream->add_option("--zoo", s.zoo_category, "a zoo shape of this category instead of a file")
                        ->check(CLI::IsMember(glimpse::zoo_categories()));
  file->excludes(zoo_shape);
  stream->add_option("--seed", s.seed, "zoo shape and random order seed")->capture_default_str();
  stream->add_option("--model", s.model, "NAME[:VERSION]")->envname("GLIMPSE_MODEL")->required()->check(kModelRef);
  stream->add_option("--method", s.method, "bok|bog|kgh|vfh|esf|ush|fusion (default: the model's)")->check(kMethod);
  auto* chunks = stream->add_option("--chunks", s.chunks, "number of chunks")->capture_default_str()
                     ->check(CLI::Range(size_t{1}, size_t{100000}));
  stream->add_option("--chunk-points", s.chunk_points, "points per chunk instead of --chunks")
      ->check(CLI::Range(size_t{1}, size_t{1000000}))->excludes(chunks);
  stream->add_option("--order", s.order, "reveal order: top-down (the paper's), random, sweep")
      ->capture_default_str()->check(kOrder);
  stream->add_option("--rate", s.rate_hz, "chunks per second, 0 = as fast as possible")->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  stream->add_option("--view", s.viewpoint, "which of the paper's 6 viewpoints (azimuth 60*N deg) sees the object")
      ->capture_default_str()->check(CLI::Range(0, 5));
  stream->add_flag("--json", s.json, "one JSON object per decision");
  AddMeshOptions(*stream, s.views);
  stream->callback([&] { run = [&] { return RunStream(conn, s); }; });

  try {
    app.parse(argc, argv);
    if (train->parsed() && t.dir.empty() && !t.zoo) throw CLI::RequiredError("train needs DIR or --zoo");
    if (stream->parsed() && s.file.empty() && s.zoo_category.empty())
      throw CLI::RequiredError("stream needs FILE or --zoo CATEGORY");
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints help/version (code 0) or the error
    return code == 0 ? kExitOk : kExitUsage;
  }
  return run ? run() : kExitUsage;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "glimpse: fatal: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "glimpse: fatal: unknown error\n");
  }
  return kExitError;
}

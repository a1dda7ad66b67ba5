// The glimpse subcommands: each takes the connection options and its own options, talks to the
// server through the generated stubs, prints its result, and returns an exit code (connection.h).
// Errors go to stderr as "glimpse: <command> <subject>: <CODE>: <message>". Nothing throws.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "client/connection.h"
#include "client/inputs.h"

namespace glimpse::client {

// grpc.health.v1.Health/Check of `service` ("" = the whole server); 0 only when SERVING.
int RunHealth(const ConnectionOptions& conn, const std::string& service);

// Model references are "NAME[:VERSION]" already checked by ParseModelRef.
int RunModelsList(const ConnectionOptions& conn, const std::string& name, bool json);
int RunModelsShow(const ConnectionOptions& conn, const std::string& ref, bool json);
int RunModelsDelete(const ConnectionOptions& conn, const std::string& ref);
int RunModelsSetDefault(const ConnectionOptions& conn, const std::string& ref);

struct TrainOptions {
  std::string dir;             // DIR/<category>/<files>; empty with zoo
  bool zoo = false;            // the core's procedural shape zoo instead of files
  size_t per_category = 4;     // zoo objects per category
  uint64_t seed = 1;           // zoo shapes, surface sampling
  std::string name;
  std::string methods;         // "bok,bog"; empty: the server's default set
  std::string description;
  ViewOptions views;
  std::optional<uint64_t> train_seed;  // TrainParameters.seed
  bool json = false;           // print the stored ModelInfo as JSON instead of a summary
  bool quiet = false;          // no progress
};
int RunTrain(const ConnectionOptions& conn, const TrainOptions& options);

struct ClassifyOptions {
  std::vector<std::string> files;
  std::string model;   // "NAME[:VERSION]"
  std::string method;  // empty: the model's default
  ViewOptions views;   // mesh sampling
  bool json = false;
};
int RunClassify(const ConnectionOptions& conn, const ClassifyOptions& options);

struct StreamOptions {
  std::string file;           // or zoo_category
  std::string zoo_category;
  uint64_t seed = 1;
  std::string model;
  std::string method;
  size_t chunks = 20;         // used when chunk_points == 0
  size_t chunk_points = 0;
  std::string order = "top-down";
  double rate_hz = 5.0;       // chunks per second; 0: as fast as the server answers
  int viewpoint = 0;          // which of the paper's six viewpoints takes the single view
  ViewOptions views;          // mesh sampling, HPR radius
  bool json = false;
};
int RunStream(const ConnectionOptions& conn, const StreamOptions& options);

}  // namespace glimpse::client

// glimpse-server configuration: defaults here, then GLIMPSE_* environment variables, then flags.
#pragma once

#include <chrono>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "glimpse/expected.h"
#include "limits.h"
#include "security.h"
#include "store.h"

namespace glimpse::server {

struct ServerConfig {
  std::string address = "0.0.0.0:50051";
  std::string db_path = kDefaultDbPath;
  int metrics_port = 9464;   // Prometheus /metrics; 0 disables
  int threads = 0;           // gRPC worker threads; 0: max streams + 2 per usable CPU (at least 4)
  int request_threads = 0;   // threads one request computes with; 0: the CPUs the process may use
  std::chrono::seconds shutdown_grace{10};  // in-flight calls get this long after SIGTERM/SIGINT
  Limits limits;
  TlsFiles tls;                 // --tls-cert/--tls-key [/--tls-client-ca]; empty: plaintext
  std::string auth_token;       // required on Train/DeleteModel/SetDefaultModel; empty: open
  std::string auth_token_file;  // read at startup (main.cc); excludes auth_token
  bool help = false;
};

using EnvFn = std::function<std::optional<std::string>(const std::string&)>;
EnvFn ProcessEnv();  // std::getenv

// args excludes argv[0]. Flags: --name=value or --name value. Unknown flags, bad numbers and flags
// that need each other (--tls-cert with --tls-key, ...) are INVALID_ARGUMENT, naming the flag or
// variable (never a token's value).
Expected<ServerConfig> ParseConfig(const std::vector<std::string>& args, const EnvFn& env);
std::string Usage();
// gRPC worker threads: config.threads, else max streams + 2 per usable CPU (at least 4), where
// `cpus` is what the process may use (ProcessCpus(), cpus.h), not the node's core count.
int EffectiveThreads(const ServerConfig& config, int cpus);
// Threads one request (a Classify, a batch, a Train) computes with: config.request_threads, else `cpus`.
int RequestThreads(const ServerConfig& config, int cpus);
// gRPC completion queues of the sync server (each has its own pollers): one per usable CPU, at most 4.
int CompletionQueues(int cpus);

}  // namespace glimpse::server

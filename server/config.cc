#include "config.h"

#include <charconv>
#include <limits>
#include <cstdlib>
#include <algorithm>

namespace glimpse::server {
namespace {

struct Option {
  const char* flag;  // without "--"
  const char* env;
  const char* value;  // placeholder in --help: N, S, FILE
  const char* help;
  std::function<Status(ServerConfig&, const std::string&)> set;
};

// A number in [min, max]: the largest values are bounded where a conversion would overflow (a stream
// limit as int threads, seconds as steady_clock nanoseconds) and a huge setting turned into a tiny one.
template <class T>
Status ParseNumber(const std::string& text, T min, T& out, T max = std::numeric_limits<T>::max()) {
  T v{};
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || v < min || v > max)
    return invalid_argument("'" + text + "' is not a number in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  out = v;
  return {};
}

template <class T>
std::function<Status(ServerConfig&, const std::string&)> Number(T ServerConfig::*field, T min,
                                                                T max = std::numeric_limits<T>::max()) {
  return [field, min, max](ServerConfig& c, const std::string& v) { return ParseNumber(v, min, c.*field, max); };
}

template <class T>
std::function<Status(ServerConfig&, const std::string&)> Limit(T Limits::*field, T min,
                                                               T max = std::numeric_limits<T>::max()) {
  return [field, min, max](ServerConfig& c, const std::string& v) { return ParseNumber(v, min, c.limits.*field, max); };
}

constexpr long long kMaxSeconds = 100LL * 365 * 24 * 3600;  // a century: "no limit" in practice

std::function<Status(ServerConfig&, const std::string&)> Seconds(std::chrono::seconds* (*get)(ServerConfig&)) {
  return [get](ServerConfig& c, const std::string& v) {
    long long s = 0;
    if (Status st = ParseNumber(v, 1LL, s, kMaxSeconds); !st.ok()) return st;
    *get(c) = std::chrono::seconds(s);
    return Status{};
  };
}

// A non-empty string field (a path).
std::function<Status(ServerConfig&, const std::string&)> Text(std::string* (*get)(ServerConfig&)) {
  return [get](ServerConfig& c, const std::string& v) {
    if (v.empty()) return Status(invalid_argument("empty value"));
    *get(c) = v;
    return Status{};
  };
}

// Flags that only make sense together.
Status CheckCombinations(const ServerConfig& c) {
  if (c.tls.cert.empty() != c.tls.key.empty()) return invalid_argument("--tls-cert and --tls-key go together");
  if (!c.tls.client_ca.empty() && c.tls.cert.empty())
    return invalid_argument("--tls-client-ca (mutual TLS) needs --tls-cert and --tls-key");
  return {};
}

const std::vector<Option>& Options() {
  static const std::vector<Option> options = {
      {"address", "GLIMPSE_ADDRESS", "S", "gRPC listen address [0.0.0.0:50051]",
       [](ServerConfig& c, const std::string& v) {
         if (v.empty()) return Status(invalid_argument("empty address"));
         c.address = v;
         return Status{};
       }},
      {"db", "GLIMPSE_DB", "FILE", "SQLite model store; its folder is created [./var/glimpse.db]",
       [](ServerConfig& c, const std::string& v) {
         if (v.empty()) return Status(invalid_argument("empty database path"));
         c.db_path = v;
         return Status{};
       }},
      {"metrics-port", "GLIMPSE_METRICS_PORT", "N", "Prometheus /metrics HTTP port, 0 disables [9464]",
       Number(&ServerConfig::metrics_port, 0)},
      {"threads", "GLIMPSE_THREADS", "N", "gRPC worker threads, 0 = max streams + 2 per usable CPU [0]",
       Number(&ServerConfig::threads, 0, 100000)},
      {"request-threads", "GLIMPSE_REQUEST_THREADS", "N",
       "threads one request computes with, 0 = the CPUs the process may use (affinity, cgroup quota) [0]",
       Number(&ServerConfig::request_threads, 0)},
      {"shutdown-grace-seconds", "GLIMPSE_SHUTDOWN_GRACE_SECONDS", "N",
       "how long in-flight calls may finish after SIGTERM/SIGINT [10]",
       Seconds([](ServerConfig& c) { return &c.shutdown_grace; })},
      {"max-message-bytes", "GLIMPSE_MAX_MESSAGE_BYTES", "N", "largest gRPC message [67108864]",
       Limit(&Limits::max_message_bytes, size_t{1024})},
      {"max-points", "GLIMPSE_MAX_POINTS", "N", "points per cloud or chunk, and per ClassifyBatch call [1000000]",
       Limit(&Limits::max_points_per_cloud, size_t{1})},
      {"max-streams", "GLIMPSE_MAX_STREAMS", "N", "concurrent Train/StreamClassify calls [64]",
       Limit(&Limits::max_concurrent_streams, size_t{1}, size_t{100000})},
      {"max-stream-seconds", "GLIMPSE_MAX_STREAM_SECONDS", "N",
       "longest StreamClassify call, and Train while receiving [600]",
       Seconds([](ServerConfig& c) { return &c.limits.max_stream_duration; })},
      {"max-train-clouds", "GLIMPSE_MAX_TRAIN_CLOUDS", "N", "clouds per Train call [100000]",
       Limit(&Limits::max_train_clouds, size_t{1})},
      {"max-train-points", "GLIMPSE_MAX_TRAIN_POINTS", "N", "points summed over a Train call [50000000]",
       Limit(&Limits::max_train_points, size_t{1})},
      {"max-session-points", "GLIMPSE_MAX_SESSION_POINTS", "N", "points accumulated by one scan session [1000000]",
       Limit(&Limits::max_session_points, size_t{1})},
      {"max-batch-clouds", "GLIMPSE_MAX_BATCH_CLOUDS", "N", "clouds per ClassifyBatch call [256]",
       Limit(&Limits::max_batch_clouds, size_t{1})},
      {"max-cached-models", "GLIMPSE_MAX_CACHED_MODELS", "N", "deserialized models kept in memory [16]",
       Limit(&Limits::max_cached_models, size_t{1})},
      {"max-training-set-bytes", "GLIMPSE_MAX_TRAINING_SET_BYTES", "N",
       "largest training set kept beside a model so it can grow (train --base), compressed; 0 keeps none [268435456]",
       Limit(&Limits::max_training_set_bytes, size_t{0})},
      {"tls-cert", "GLIMPSE_TLS_CERT", "FILE", "PEM server certificate (chain); with --tls-key serves TLS only",
       Text([](ServerConfig& c) { return &c.tls.cert; })},
      {"tls-key", "GLIMPSE_TLS_KEY", "FILE", "PEM private key of --tls-cert", Text([](ServerConfig& c) { return &c.tls.key; })},
      {"tls-client-ca", "GLIMPSE_TLS_CLIENT_CA", "FILE",
       "PEM CA: mutual TLS, every client must present a certificate it signed",
       Text([](ServerConfig& c) { return &c.tls.client_ca; })},
      {"auth-token", "GLIMPSE_AUTH_TOKEN", "S",
       "bearer token Train/DeleteModel/SetDefaultModel require (prefer the file: flags show in ps)",
       [](ServerConfig& c, const std::string& v) {
         if (Status s = ValidateToken(v); !s.ok()) return s;
         c.auth_token = v;
         c.auth_token_file.clear();  // the later setting wins (flags over environment)
         return Status{};
       }},
      {"auth-token-file", "GLIMPSE_AUTH_TOKEN_FILE", "FILE", "file whose first line is the bearer token",
       [](ServerConfig& c, const std::string& v) {
         if (v.empty()) return Status(invalid_argument("empty value"));
         c.auth_token_file = v;
         c.auth_token.clear();
         return Status{};
       }},
  };
  return options;
}

}  // namespace

EnvFn ProcessEnv() {
  return [](const std::string& name) -> std::optional<std::string> {
    const char* v = std::getenv(name.c_str());
    return v ? std::optional<std::string>(v) : std::nullopt;
  };
}

Expected<ServerConfig> ParseConfig(const std::vector<std::string>& args, const EnvFn& env) {
  ServerConfig config;
  for (const Option& o : Options()) {
    if (auto v = env ? env(o.env) : std::nullopt) {
      if (Status s = o.set(config, *v); !s.ok()) return invalid_argument(std::string(o.env) + ": " + s.error().message);
    }
  }
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg == "--help" || arg == "-h") {
      config.help = true;
      continue;
    }
    if (arg.rfind("--", 0) != 0) return invalid_argument("unexpected argument '" + arg + "' (see --help)");
    std::string name = arg.substr(2), value;
    bool has_value = false;
    if (auto eq = name.find('='); eq != std::string::npos) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
      has_value = true;
    }
    const Option* option = nullptr;
    for (const Option& o : Options())
      if (name == o.flag) option = &o;
    if (!option) return invalid_argument("unknown flag --" + name + " (see --help)");
    if (!has_value) {
      if (i + 1 >= args.size()) return invalid_argument("--" + name + " needs a value");
      value = args[++i];
    }
    if (Status s = option->set(config, value); !s.ok()) return invalid_argument("--" + name + ": " + s.error().message);
  }
  if (Status s = CheckCombinations(config); !s.ok()) return s.error();
  return config;
}

std::string Usage() {
  std::string out =
      "glimpse-server: the glimpse.v1.Glimpse gRPC service (recognise object categories from partial point\n"
      "clouds) with a SQLite model store, gRPC health checking and reflection, and Prometheus metrics.\n\n"
      "usage: glimpse-server [--flag=value ...]\n\n"
      "Every flag can also be set by its environment variable; flags win.\n\n";
  for (const Option& o : Options()) {
    std::string left = "  --" + std::string(o.flag) + "=" + o.value;
    left.resize(std::max<size_t>(left.size() + 1, 28), ' ');
    std::string env = o.env;
    env.resize(std::max<size_t>(env.size() + 1, 32), ' ');
    out += left + env + o.help + "\n";
  }
  out += "  --help                      this text\n\n"
         "SIGTERM/SIGINT: stop accepting calls, let in-flight ones finish (up to the grace period), close the store.\n"
         "With a token, Train, DeleteModel and SetDefaultModel need the metadata 'authorization: Bearer <token>'\n"
         "(else UNAUTHENTICATED); Classify, StreamClassify, ListModels, GetModel and health stay open. Send the\n"
         "token over TLS only: on a plaintext port anyone on the path can read it.\n";
  return out;
}

int EffectiveThreads(const ServerConfig& config, int cpus) {
  if (config.threads > 0) return config.threads;
  return static_cast<int>(config.limits.max_concurrent_streams) + std::max(4, 2 * std::max(1, cpus));
}

int RequestThreads(const ServerConfig& config, int cpus) {
  return config.request_threads > 0 ? config.request_threads : std::max(1, cpus);
}

int CompletionQueues(int cpus) { return std::clamp(cpus, 1, 4); }

}  // namespace glimpse::server

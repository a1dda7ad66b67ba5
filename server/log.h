// One structured line per request: what was asked (RPC, model, method, sizes), how long it took and
// how it ended. Never the cloud data, never metadata such as tokens.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

namespace glimpse::server {

struct RequestLog {
  std::string rpc;
  std::string peer;
  std::string model;   // "name@version" once resolved, else the name asked for
  std::string method;  // recognition method, when the RPC has one
  uint64_t points = 0;
  uint64_t messages = 0;  // streamed messages received
  double latency_ms = 0;
  std::string code;     // gRPC status code name
  std::string message;  // the error message, empty on success
};

using LogFn = std::function<void(const RequestLog&)>;

// RequestLog::model: "name@3", or "name" for version 0.
std::string LogModelRef(std::string_view name, uint32_t version);

// logfmt: `ts=... level=info rpc=Classify model=chairs@3 ... code=OK`, one write per line.
std::string FormatLogLine(const RequestLog& entry);
void LogToStderr(const RequestLog& entry);
// Server lifecycle lines (start, shutdown) in the same format.
void LogEvent(const std::string& level, const std::string& message);

}  // namespace glimpse::server

#include "log.h"

#include <chrono>
#include <cstdio>
#include <ctime>

namespace glimpse::server {
namespace {

std::string Timestamp() {
  using namespace std::chrono;
  const auto now = system_clock::now();
  const std::time_t t = system_clock::to_time_t(now);
  const auto ms = duration_cast<milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900, tm.tm_mon + 1,
                tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(ms));
  return buf;
}

// Quotes a value when it has spaces, quotes or control characters (logfmt).
std::string Value(const std::string& v) {
  bool plain = !v.empty();
  for (unsigned char c : v)
    if (c <= ' ' || c == '"' || c == '=' || c == '\\' || c >= 0x7f) plain = false;
  if (plain) return v;
  std::string out = "\"";
  for (unsigned char c : v) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < ' ' || c == 0x7f) {
      out += ' ';
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "\"";
}

void Write(const std::string& line) {
  std::string l = line + "\n";
  std::fwrite(l.data(), 1, l.size(), stderr);  // one write, so lines from threads do not interleave
}

}  // namespace

std::string LogModelRef(std::string_view name, uint32_t version) {
  return version ? std::string(name) + "@" + std::to_string(version) : std::string(name);
}

std::string FormatLogLine(const RequestLog& e) {
  char latency[32];
  std::snprintf(latency, sizeof latency, "%.3f", e.latency_ms);
  std::string line = "ts=" + Timestamp() + " level=" + (e.code == "OK" ? "info" : "warn") + " rpc=" + Value(e.rpc);
  if (!e.peer.empty()) line += " peer=" + Value(e.peer);
  if (!e.model.empty()) line += " model=" + Value(e.model);
  if (!e.method.empty()) line += " method=" + Value(e.method);
  line += " points=" + std::to_string(e.points);
  if (e.messages) line += " messages=" + std::to_string(e.messages);
  line += " latency_ms=" + std::string(latency) + " code=" + Value(e.code);
  if (!e.message.empty()) line += " error=" + Value(e.message.substr(0, 512));
  return line;
}

void LogToStderr(const RequestLog& entry) { Write(FormatLogLine(entry)); }

void LogEvent(const std::string& level, const std::string& message) {
  Write("ts=" + Timestamp() + " level=" + Value(level) + " msg=" + Value(message));
}

}  // namespace glimpse::server

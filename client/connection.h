// What every command shares: the channel (plain or TLS), per-call deadline and bearer token, and
// how errors are reported ("glimpse: <what>: <CODE>: <message>" on stderr).
#pragma once

#include <grpcpp/channel.h>
#include <grpcpp/client_context.h>

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "glimpse/expected.h"
#include "glimpse/v1/glimpse.grpc.pb.h"

namespace glimpse::client {

// Exit codes of the glimpse command.
inline constexpr int kExitOk = 0;
inline constexpr int kExitError = 1;
inline constexpr int kExitUsage = 2;

struct ConnectionOptions {
  std::string server = "localhost:50051";
  std::optional<double> timeout_s;  // unset: the command's default
  bool tls = false;
  std::string ca_file, cert_file, key_file;  // PEM; ca empty: the system roots
  std::string token;                          // sent as "authorization: Bearer <token>" when set
};

// Reads the PEM files (errors name them). The channel connects lazily.
Expected<std::shared_ptr<grpc::Channel>> MakeChannel(const ConnectionOptions& options);

// Deadline (options.timeout_s, else default_timeout_s) and the token on one call's context.
void PrepareContext(grpc::ClientContext& context, const ConnectionOptions& options, double default_timeout_s);

// A glimpse.v1.Glimpse stub over MakeChannel, or nullptr after printing the error for `what`.
std::unique_ptr<v1::Glimpse::Stub> ConnectGlimpse(const ConnectionOptions& options, std::string_view what);

// "NOT_FOUND: model 'x' not found"
std::string FormatStatus(const grpc::Status& status);

// "glimpse: <what>: <detail>\n" on stderr.
void PrintError(std::string_view what, std::string_view detail);

// Writes text to stdout as it is.
void PrintOut(std::string_view text);

// Whether the stream is a terminal (live redraws) or a pipe/file (plain lines).
bool IsTerminal(std::FILE* stream);

}  // namespace glimpse::client

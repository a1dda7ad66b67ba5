#include "client/connection.h"

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include "proto/wire/errors.h"

namespace glimpse::client {
namespace {

Expected<std::string> ReadPem(const std::string& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return not_found(path + ": cannot read the " + std::string(what));
  std::ostringstream text;
  text << in.rdbuf();
  if (text.str().empty()) return invalid_argument(path + ": empty " + std::string(what));
  return text.str();
}

}  // namespace

Expected<std::shared_ptr<grpc::Channel>> MakeChannel(const ConnectionOptions& options) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(64 << 20);  // the server's default limit
  args.SetMaxSendMessageSize(64 << 20);
  if (!options.tls) {
    if (!options.ca_file.empty() || !options.cert_file.empty() || !options.key_file.empty())
      return invalid_argument("--ca, --cert and --key need --tls");
    return grpc::CreateCustomChannel(options.server, grpc::InsecureChannelCredentials(), args);
  }
  if (options.cert_file.empty() != options.key_file.empty())
    return invalid_argument("--cert and --key go together (client certificate and its private key)");
  grpc::SslCredentialsOptions ssl;
  if (!options.ca_file.empty()) {
    auto ca = ReadPem(options.ca_file, "CA certificate");
    if (!ca) return ca.error();
    ssl.pem_root_certs = std::move(*ca);
  }
  if (!options.cert_file.empty()) {
    auto cert = ReadPem(options.cert_file, "client certificate");
    if (!cert) return cert.error();
    auto key = ReadPem(options.key_file, "client key");
    if (!key) return key.error();
    ssl.pem_cert_chain = std::move(*cert);
    ssl.pem_private_key = std::move(*key);
  }
  return grpc::CreateCustomChannel(options.server, grpc::SslCredentials(ssl), args);
}

void PrepareContext(grpc::ClientContext& context, const ConnectionOptions& options, double default_timeout_s) {
  const double seconds = options.timeout_s.value_or(default_timeout_s);
  if (seconds > 0)
    context.set_deadline(std::chrono::system_clock::now() +
                         std::chrono::duration_cast<std::chrono::system_clock::duration>(
                             std::chrono::duration<double>(seconds)));
  // Plain metadata rather than call credentials: gRPC only sends those over TLS, and a token may be
  // wanted on a loopback test server too.
  if (!options.token.empty()) context.AddMetadata("authorization", "Bearer " + options.token);
}

std::unique_ptr<v1::Glimpse::Stub> ConnectGlimpse(const ConnectionOptions& options, std::string_view what) {
  auto channel = MakeChannel(options);
  if (!channel) {
    PrintError(what, channel.error().message);
    return nullptr;
  }
  return v1::Glimpse::NewStub(*channel);
}

std::string FormatStatus(const grpc::Status& status) {
  std::string out = wire::StatusCodeName(status.error_code());
  if (!status.error_message().empty()) out += ": " + status.error_message();
  return out;
}

void PrintError(std::string_view what, std::string_view detail) {
  std::string line = "glimpse: ";
  line += what;
  if (!detail.empty()) {
    line += ": ";
    line += detail;
  }
  line += "\n";
  std::fwrite(line.data(), 1, line.size(), stderr);
}

void PrintOut(std::string_view text) {
  std::fwrite(text.data(), 1, text.size(), stdout);
  std::fflush(stdout);
}

bool IsTerminal(std::FILE* stream) { return ::isatty(::fileno(stream)) == 1; }

}  // namespace glimpse::client

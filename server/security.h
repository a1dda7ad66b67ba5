// Transport and caller security of glimpse-server: TLS (optionally mutual) credentials from PEM files,
// and the bearer token that guards the RPCs which change models (Train, DeleteModel, SetDefaultModel).
// Neither the token nor key material is ever logged or put into an error message.
#pragma once

#include <grpcpp/security/server_credentials.h>
#include <grpcpp/support/string_ref.h>

#include <array>
#include <map>
#include <memory>
#include <string>
#include <string_view>

#include "glimpse/expected.h"

namespace glimpse::server {

// PEM file paths. cert and key go together; client_ca (optional) turns on mutual TLS: every client
// must present a certificate signed by it.
struct TlsFiles {
  std::string cert;
  std::string key;
  std::string client_ca;
  bool enabled() const { return !cert.empty(); }
};

// Reads and checks the PEM files (the certificate parses, the key parses and matches it, the CA
// parses). Errors name the file, never its contents.
Expected<std::shared_ptr<grpc::ServerCredentials>> LoadServerCredentials(const TlsFiles& files);

// The first line of a token file, without its line end. INVALID_ARGUMENT when empty or when it holds
// characters outside printable ASCII (0x21-0x7e), which a metadata value cannot carry.
Expected<std::string> ReadTokenFile(const std::string& path);
Status ValidateToken(std::string_view token);

// A configured bearer token, held as its SHA-256 digest: a presented token is hashed and the digests
// are compared in constant time, so neither the content nor the length of the token leaks through
// timing. An empty token accepts every caller.
class BearerToken {
 public:
  BearerToken() = default;
  explicit BearerToken(std::string_view token);
  bool required() const { return required_; }
  // True when no token is required, or the metadata has `authorization: Bearer <token>`.
  bool Accepts(const std::multimap<grpc::string_ref, grpc::string_ref>& metadata) const;
  bool Matches(std::string_view presented) const;

 private:
  bool required_ = false;
  std::array<unsigned char, 32> digest_{};
};

}  // namespace glimpse::server

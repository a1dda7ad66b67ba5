#include "security.h"

#include <openssl/bio.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/sha.h>
#include <openssl/x509.h>

#include <cctype>
#include <fstream>
#include <sstream>

namespace glimpse::server {
namespace {

constexpr size_t kMaxPemBytes = 1 << 20;

Expected<std::string> ReadSmallFile(const std::string& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return not_found(std::string(what) + " " + path + ": cannot be read");
  std::ostringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  if (s.empty()) return invalid_argument(std::string(what) + " " + path + ": empty file");
  if (s.size() > kMaxPemBytes) return invalid_argument(std::string(what) + " " + path + ": larger than 1 MiB");
  return s;
}

struct BioFree {
  void operator()(BIO* b) const { BIO_free(b); }
};
struct X509Free {
  void operator()(X509* x) const { X509_free(x); }
};
struct KeyFree {
  void operator()(EVP_PKEY* k) const { EVP_PKEY_free(k); }
};

std::unique_ptr<BIO, BioFree> Bio(const std::string& pem) {
  return std::unique_ptr<BIO, BioFree>(BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size())));
}

std::unique_ptr<X509, X509Free> ParseCert(const std::string& pem) {
  auto bio = Bio(pem);
  return std::unique_ptr<X509, X509Free>(bio ? PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr) : nullptr);
}

std::array<unsigned char, 32> Sha256(std::string_view s) {
  std::array<unsigned char, 32> d{};
  SHA256(reinterpret_cast<const unsigned char*>(s.data()), s.size(), d.data());
  return d;
}

}  // namespace

Expected<std::shared_ptr<grpc::ServerCredentials>> LoadServerCredentials(const TlsFiles& files) {
  if (files.cert.empty() != files.key.empty())
    return invalid_argument("--tls-cert and --tls-key go together");
  if (files.cert.empty()) {
    if (!files.client_ca.empty()) return invalid_argument("--tls-client-ca needs --tls-cert and --tls-key");
    return grpc::InsecureServerCredentials();
  }
  auto cert = ReadSmallFile(files.cert, "TLS certificate");
  if (!cert) return cert.error();
  auto key = ReadSmallFile(files.key, "TLS key");
  if (!key) return key.error();
  auto x509 = ParseCert(*cert);
  if (!x509) return invalid_argument("TLS certificate " + files.cert + ": not a PEM certificate");
  auto key_bio = Bio(*key);
  std::unique_ptr<EVP_PKEY, KeyFree> pkey(
      key_bio ? PEM_read_bio_PrivateKey(key_bio.get(), nullptr, nullptr, nullptr) : nullptr);
  if (!pkey) return invalid_argument("TLS key " + files.key + ": not an unencrypted PEM private key");
  if (X509_check_private_key(x509.get(), pkey.get()) != 1)
    return invalid_argument("TLS key " + files.key + " does not belong to the certificate " + files.cert);

  grpc::SslServerCredentialsOptions options(GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE);
  options.pem_key_cert_pairs.push_back({*key, *cert});
  if (!files.client_ca.empty()) {
    auto ca = ReadSmallFile(files.client_ca, "TLS client CA");
    if (!ca) return ca.error();
    if (!ParseCert(*ca)) return invalid_argument("TLS client CA " + files.client_ca + ": not a PEM certificate");
    options.pem_root_certs = *ca;
    options.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
  }
  return grpc::SslServerCredentials(options);
}

Status ValidateToken(std::string_view token) {
  if (token.empty()) return invalid_argument("the auth token is empty");
  for (unsigned char c : token)
    if (c < 0x21 || c > 0x7e) return invalid_argument("the auth token may only hold printable ASCII without blanks");
  return {};
}

Expected<std::string> ReadTokenFile(const std::string& path) {
  auto text = ReadSmallFile(path, "auth token file");
  if (!text) return text.error();
  std::string token = text->substr(0, text->find('\n'));
  if (!token.empty() && token.back() == '\r') token.pop_back();
  if (Status s = ValidateToken(token); !s.ok()) return invalid_argument("auth token file " + path + ": " + s.error().message);
  return token;
}

BearerToken::BearerToken(std::string_view token) : required_(!token.empty()), digest_(Sha256(token)) {}

bool BearerToken::Matches(std::string_view presented) const {
  const auto d = Sha256(presented);
  return CRYPTO_memcmp(d.data(), digest_.data(), d.size()) == 0;
}

bool BearerToken::Accepts(const std::multimap<grpc::string_ref, grpc::string_ref>& metadata) const {
  if (!required_) return true;
  bool ok = false;
  auto [begin, end] = metadata.equal_range("authorization");
  for (auto it = begin; it != end; ++it) {
    std::string_view value(it->second.data(), it->second.size());
    constexpr std::string_view kScheme = "bearer ";
    if (value.size() < kScheme.size()) continue;
    bool scheme = true;  // the scheme is case-insensitive (RFC 6750 / 7235)
    for (size_t i = 0; i < kScheme.size(); ++i)
      scheme = scheme && static_cast<char>(std::tolower(static_cast<unsigned char>(value[i]))) == kScheme[i];
    if (scheme && Matches(value.substr(kScheme.size()))) ok = true;
  }
  return ok;
}

}  // namespace glimpse::server

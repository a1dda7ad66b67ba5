// Security of the service: the TLS and token flags, the bearer token compared by digest, and which
// RPCs need it (exactly Train, DeleteModel, SetDefaultModel). TLS itself, with certificates made at
// test time, is checked end to end with the glimpse CLI in tests/reliability/security_test.sh.
#include <gmock/gmock.h>
#include <gtest/gtest.h>


#include "common/temp_dir.h"
#include "fakes.h"
#include "server/config.h"
#include "server/security.h"

namespace glimpse::server {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
using testing::Harness;
using testing::SpiralCloud;
using glimpse::testing::TempDir;

constexpr const char* kToken = "tok-3f9a1c77e2";

EnvFn Env(std::map<std::string, std::string> vars) {
  return [vars](const std::string& k) -> std::optional<std::string> {
    auto it = vars.find(k);
    return it == vars.end() ? std::nullopt : std::optional<std::string>(it->second);
  };
}

// ---------------------------------------------------------------------------------------------
// Flags

TEST(SecurityConfig, TlsAndTokenFlagsAndVariables) {
  auto c = ParseConfig({"--tls-cert=/c.pem", "--tls-key", "/k.pem", "--tls-client-ca=/ca.pem", "--auth-token-file=/t"},
                       Env({{"GLIMPSE_AUTH_TOKEN", "from-env"}}));
  ASSERT_TRUE(c.ok()) << c.error().message;
  EXPECT_EQ(c->tls.cert, "/c.pem");
  EXPECT_EQ(c->tls.key, "/k.pem");
  EXPECT_EQ(c->tls.client_ca, "/ca.pem");
  EXPECT_TRUE(c->tls.enabled());
  EXPECT_EQ(c->auth_token_file, "/t");
  EXPECT_EQ(c->auth_token, "");  // the flag wins over the variable
  auto env = ParseConfig({}, Env({{"GLIMPSE_AUTH_TOKEN", kToken}, {"GLIMPSE_TLS_CERT", "/c"}, {"GLIMPSE_TLS_KEY", "/k"}}));
  ASSERT_TRUE(env.ok()) << env.error().message;
  EXPECT_EQ(env->auth_token, kToken);
  EXPECT_EQ(env->tls.cert, "/c");
  auto defaults = ParseConfig({}, Env({}));
  ASSERT_TRUE(defaults.ok());
  EXPECT_FALSE(defaults->tls.enabled());
  EXPECT_TRUE(defaults->auth_token.empty());
  for (const char* s : {"--tls-cert", "--tls-key", "--tls-client-ca", "--auth-token", "--auth-token-file",
                        "GLIMPSE_AUTH_TOKEN_FILE", "UNAUTHENTICATED"})
    EXPECT_THAT(Usage(), HasSubstr(s));
}

TEST(SecurityConfig, FlagsThatNeedEachOtherAndBadTokensAreRejectedWithoutEchoingTheToken) {
  EXPECT_FALSE(ParseConfig({"--tls-cert=/c.pem"}, Env({})).ok());
  EXPECT_FALSE(ParseConfig({"--tls-key=/k.pem"}, Env({})).ok());
  auto ca = ParseConfig({"--tls-client-ca=/ca.pem"}, Env({}));
  ASSERT_FALSE(ca.ok());
  EXPECT_THAT(ca.error().message, HasSubstr("--tls-client-ca"));
  auto blank = ParseConfig({"--auth-token=has blank-secret"}, Env({}));
  ASSERT_FALSE(blank.ok());
  EXPECT_THAT(blank.error().message, HasSubstr("--auth-token"));
  EXPECT_THAT(blank.error().message, Not(HasSubstr("secret")));
  auto env = ParseConfig({}, Env({{"GLIMPSE_AUTH_TOKEN", "tab\tsecret"}}));
  ASSERT_FALSE(env.ok());
  EXPECT_THAT(env.error().message, HasSubstr("GLIMPSE_AUTH_TOKEN"));
  EXPECT_THAT(env.error().message, Not(HasSubstr("secret")));
  EXPECT_FALSE(ParseConfig({"--auth-token="}, Env({})).ok());
}

TEST(SecurityFiles, TokenFileIsItsFirstLine) {
  TempDir dir;
  auto t = ReadTokenFile(dir.Write("t", std::string(kToken) + "\r\nignored\n"));
  ASSERT_TRUE(t.ok()) << t.error().message;
  EXPECT_EQ(*t, kToken);
  EXPECT_FALSE(ReadTokenFile(dir.Write("empty", "")).ok());
  EXPECT_FALSE(ReadTokenFile(dir.Write("blank-line", "\nsecond\n")).ok());
  auto spaced = ReadTokenFile(dir.Write("spaced", "two words-secret\n"));
  ASSERT_FALSE(spaced.ok());
  EXPECT_THAT(spaced.error().message, Not(HasSubstr("secret")));
  EXPECT_EQ(ReadTokenFile("/nonexistent/token").error().code, ErrorCode::kNotFound);
}

TEST(SecurityFiles, BadPemFilesAreClearErrorsNamingTheFile) {
  TempDir dir;
  EXPECT_TRUE(LoadServerCredentials(TlsFiles{}).ok());  // plaintext
  const std::string junk = dir.Write("junk.pem", "-----BEGIN CERTIFICATE-----\nbm90IGEgY2VydA==\n-----END CERTIFICATE-----\n");
  auto bad = LoadServerCredentials(TlsFiles{junk, junk, ""});
  ASSERT_FALSE(bad.ok());
  EXPECT_THAT(bad.error().message, HasSubstr("junk.pem"));
  EXPECT_THAT(bad.error().message, HasSubstr("not a PEM certificate"));
  auto missing = LoadServerCredentials(TlsFiles{"/nonexistent/cert.pem", "/nonexistent/key.pem", ""});
  ASSERT_FALSE(missing.ok());
  EXPECT_THAT(missing.error().message, HasSubstr("/nonexistent/cert.pem"));
  EXPECT_FALSE(LoadServerCredentials(TlsFiles{"", "", junk}).ok());  // mutual TLS without a certificate
}

// ---------------------------------------------------------------------------------------------
// The token

std::multimap<grpc::string_ref, grpc::string_ref> Metadata(const std::vector<std::pair<std::string, std::string>>& kv) {
  static std::vector<std::pair<std::string, std::string>> storage;  // string_ref does not own
  storage = kv;
  std::multimap<grpc::string_ref, grpc::string_ref> md;
  for (const auto& [k, v] : storage) md.emplace(grpc::string_ref(k), grpc::string_ref(v));
  return md;
}

TEST(BearerToken, AcceptsExactlyTheConfiguredToken) {
  const BearerToken open;
  EXPECT_FALSE(open.required());
  EXPECT_TRUE(open.Accepts(Metadata({})));
  const BearerToken t(kToken);
  EXPECT_TRUE(t.required());
  EXPECT_TRUE(t.Matches(kToken));
  EXPECT_FALSE(t.Matches(""));
  EXPECT_FALSE(t.Matches(std::string(kToken) + "x"));
  EXPECT_FALSE(t.Matches(std::string(kToken).substr(1)));
  EXPECT_TRUE(t.Accepts(Metadata({{"authorization", std::string("Bearer ") + kToken}})));
  EXPECT_TRUE(t.Accepts(Metadata({{"authorization", std::string("bearer ") + kToken}})));
  EXPECT_TRUE(t.Accepts(Metadata({{"authorization", "Bearer wrong"}, {"authorization", std::string("Bearer ") + kToken}})));
  EXPECT_FALSE(t.Accepts(Metadata({})));
  EXPECT_FALSE(t.Accepts(Metadata({{"authorization", kToken}})));  // no scheme
  EXPECT_FALSE(t.Accepts(Metadata({{"authorization", std::string("Basic ") + kToken}})));
  EXPECT_FALSE(t.Accepts(Metadata({{"authorization", std::string("Bearer  ") + kToken}})));
  EXPECT_FALSE(t.Accepts(Metadata({{"x-token", std::string("Bearer ") + kToken}})));
  EXPECT_FALSE(t.Accepts(Metadata({{"authorization", "Bearer "}})));
}

// ---------------------------------------------------------------------------------------------
// Which RPCs need it

struct Calls {
  Harness& h;
  std::string token;  // empty: no metadata
  void Prepare(grpc::ClientContext& ctx) const {
    if (!token.empty()) ctx.AddMetadata("authorization", "Bearer " + token);
  }
  grpc::Status Train(const std::string& name) const {
    grpc::ClientContext ctx;
    Prepare(ctx);
    auto stream = h.stub->Train(&ctx);
    v1::TrainRequest header;
    header.mutable_header()->set_model_name(name);
    stream->Write(header);
    for (const char* category : {"a", "b"}) {
      v1::TrainRequest req;
      req.mutable_cloud()->set_category(category);
      *req.mutable_cloud()->mutable_cloud() = wire::CloudToProto(SpiralCloud(40));
      stream->Write(req);
    }
    stream->WritesDone();
    for (v1::TrainProgress p; stream->Read(&p);) {
    }
    return stream->Finish();
  }
  grpc::Status Classify() const {
    grpc::ClientContext ctx;
    Prepare(ctx);
    v1::ClassifyRequest req;
    req.mutable_model()->set_name("m");
    *req.mutable_cloud() = wire::CloudToProto(SpiralCloud(30));
    v1::ClassifyResponse resp;
    return h.stub->Classify(&ctx, req, &resp);
  }
  grpc::Status Stream() const {
    grpc::ClientContext ctx;
    Prepare(ctx);
    auto stream = h.stub->StreamClassify(&ctx);
    v1::ScanChunk chunk;
    chunk.mutable_model()->set_name("m");
    *chunk.mutable_cloud() = wire::CloudToProto(SpiralCloud(30));
    stream->Write(chunk);
    v1::Decision d;
    stream->Read(&d);
    stream->WritesDone();
    while (stream->Read(&d)) {}
    return stream->Finish();
  }
  grpc::Status List() const {
    grpc::ClientContext ctx;
    Prepare(ctx);
    v1::ListModelsResponse resp;
    return h.stub->ListModels(&ctx, v1::ListModelsRequest(), &resp);
  }
  grpc::Status Get() const {
    grpc::ClientContext ctx;
    Prepare(ctx);
    v1::GetModelRequest req;
    req.mutable_model()->set_name("m");
    v1::ModelInfo resp;
    return h.stub->GetModel(&ctx, req, &resp);
  }
  grpc::Status SetDefault(uint32_t version) const {
    grpc::ClientContext ctx;
    Prepare(ctx);
    v1::SetDefaultModelRequest req;
    req.set_name("m");
    req.set_version(version);
    v1::ModelInfo resp;
    return h.stub->SetDefaultModel(&ctx, req, &resp);
  }
  grpc::Status Delete(uint32_t version) const {
    grpc::ClientContext ctx;
    Prepare(ctx);
    v1::DeleteModelRequest req;
    req.set_name("m");
    req.set_version(version);
    v1::DeleteModelResponse resp;
    return h.stub->DeleteModel(&ctx, req, &resp);
  }
};

TEST(Auth, TheTokenIsRequiredExactlyOnTheRpcsThatChangeModels) {
  Harness h(Limits{}, [](ServiceOptions& o) { o.auth_token = kToken; });
  const Calls anonymous{h, ""}, wrong{h, "not-the-token"}, authorised{h, kToken};
  for (const Calls* c : {&anonymous, &wrong}) {
    grpc::Status s = c->Train("m");
    EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAUTHENTICATED);
    EXPECT_THAT(s.error_message(), HasSubstr("authorization: Bearer"));
    EXPECT_THAT(s.error_message(), Not(HasSubstr("not-the-token")));
  }
  EXPECT_EQ(h.behaviour.train_calls.load(), 0);  // refused before any work
  EXPECT_TRUE(h.store->List()->empty());
  ASSERT_TRUE(authorised.Train("m").ok());
  ASSERT_TRUE(authorised.Train("m").ok());  // version 2

  for (const Calls* c : {&anonymous, &wrong, &authorised}) {  // reading stays open
    EXPECT_TRUE(c->Classify().ok());
    EXPECT_TRUE(c->Stream().ok());
    EXPECT_TRUE(c->List().ok());
    EXPECT_TRUE(c->Get().ok());
  }
  for (const Calls* c : {&anonymous, &wrong}) {
    EXPECT_EQ(c->SetDefault(1).error_code(), grpc::StatusCode::UNAUTHENTICATED);
    EXPECT_EQ(c->Delete(1).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  }
  EXPECT_EQ(h.store->List()->size(), 2u);
  EXPECT_EQ(h.store->Get("m", 0)->version, 2u);
  EXPECT_TRUE(authorised.SetDefault(1).ok());
  EXPECT_EQ(h.store->Get("m", 0)->version, 1u);
  EXPECT_TRUE(authorised.Delete(2).ok());
  EXPECT_EQ(h.store->List()->size(), 1u);

  EXPECT_EQ(h.metrics.RequestCount("Train", grpc::StatusCode::UNAUTHENTICATED), 2);
  for (const RequestLog& l : h.Logs()) EXPECT_THAT(FormatLogLine(l), Not(HasSubstr(kToken)));
}

TEST(Auth, WithoutATokenEverythingIsOpen) {
  Harness h;
  const Calls anonymous{h, ""};
  ASSERT_TRUE(anonymous.Train("m").ok());
  EXPECT_TRUE(anonymous.SetDefault(1).ok());
  EXPECT_TRUE(anonymous.Delete(1).ok());
}

}  // namespace
}  // namespace glimpse::server

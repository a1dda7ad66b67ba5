#include <gtest/gtest.h>
#include <grpcpp/test/client_context_test_peer.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "client/connection.h"

namespace glimpse::client {
namespace {

double SecondsUntil(std::chrono::system_clock::time_point t) {
  return std::chrono::duration<double>(t - std::chrono::system_clock::now()).count();
}

TEST(PrepareContext, DeadlineIsTheTimeoutElseTheCommandDefault) {
  ConnectionOptions options;
  grpc::ClientContext by_default;
  PrepareContext(by_default, options, 30);
  EXPECT_NEAR(SecondsUntil(by_default.deadline()), 30.0, 2.0);
  options.timeout_s = 2.5;
  grpc::ClientContext explicit_timeout;
  PrepareContext(explicit_timeout, options, 30);
  EXPECT_NEAR(SecondsUntil(explicit_timeout.deadline()), 2.5, 1.0);
}

TEST(PrepareContext, TokenIsSentAsBearerAuthorization) {
  ConnectionOptions options;
  grpc::ClientContext none;
  PrepareContext(none, options, 5);
  EXPECT_TRUE(grpc::testing::ClientContextTestPeer(&none).GetSendInitialMetadata().empty());
  options.token = "s3cret";
  grpc::ClientContext with;
  PrepareContext(with, options, 5);
  const auto metadata = grpc::testing::ClientContextTestPeer(&with).GetSendInitialMetadata();
  ASSERT_EQ(metadata.count("authorization"), 1u);
  EXPECT_EQ(metadata.find("authorization")->second, "Bearer s3cret");
}

TEST(MakeChannel, PlainAndTlsChannelsAreCreatedLazily) {
  ConnectionOptions options;
  options.server = "127.0.0.1:1";
  EXPECT_TRUE(MakeChannel(options).ok());
  options.tls = true;
  EXPECT_TRUE(MakeChannel(options).ok());  // system roots
}

TEST(MakeChannel, CertificateOptionsAreChecked) {
  ConnectionOptions options;
  options.ca_file = "/nonexistent/ca.pem";
  auto no_tls = MakeChannel(options);
  ASSERT_FALSE(no_tls.ok());
  EXPECT_NE(no_tls.error().message.find("--tls"), std::string::npos);
  options.tls = true;
  auto missing = MakeChannel(options);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("/nonexistent/ca.pem"), std::string::npos);
  options.ca_file.clear();
  options.cert_file = "/nonexistent/cert.pem";
  auto half = MakeChannel(options);
  ASSERT_FALSE(half.ok());
  EXPECT_NE(half.error().message.find("--key"), std::string::npos);
}

TEST(FormatStatus, CodeNameThenMessage) {
  EXPECT_EQ(FormatStatus(grpc::Status(grpc::StatusCode::NOT_FOUND, "model 'x' not found")),
            "NOT_FOUND: model 'x' not found");
  EXPECT_EQ(FormatStatus(grpc::Status(grpc::StatusCode::CANCELLED, "")), "CANCELLED");
}

}  // namespace
}  // namespace glimpse::client

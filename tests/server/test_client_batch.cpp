// The client's BatchClassifier against a server whose limits are below the client's own (a server run
// with --max-batch-clouds or --max-points lower than the defaults): the call refused for its size, the
// clouds are sent one by one, each answered as Classify answers it.
#include <gtest/gtest.h>

#include "client/batch_client.h"
#include "fakes.h"

namespace glimpse::server {
namespace {

using testing::Harness;
using testing::SpiralCloud;

Limits Small() {
  Limits l;
  l.max_points_per_cloud = 100;
  l.max_batch_clouds = 2;
  return l;
}

TEST(ClientBatch, ABatchOverTheServersLimitsFallsBackToOneCallPerCloud) {
  Harness h(Small());
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b", "c"}, &t).ok());
  const client::ConnectionOptions conn;
  v1::ModelRef model;
  model.set_name("m");
  // Five clouds (over 2 a call), then two of 60 points (over 100 in all); the last cloud alone is over
  // the server's 100 points and is refused alone.
  const std::vector<Cloud> clouds = {SpiralCloud(10), SpiralCloud(11), SpiralCloud(12), SpiralCloud(13),
                                     SpiralCloud(14), SpiralCloud(60), SpiralCloud(60), SpiralCloud(101)};
  client::BatchClassifier classifier(conn, *h.stub, model, v1::METHOD_UNSPECIFIED, 10.0);
  const client::BatchAnswers got = classifier.Classify(clouds);
  ASSERT_EQ(got.answers.size(), clouds.size());
  for (size_t i = 0; i + 1 < clouds.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(got.answers[i].code, grpc::StatusCode::OK) << got.answers[i].message;
    ASSERT_TRUE(got.answers[i].response.has_value());
    EXPECT_EQ(got.answers[i].response->points(), clouds[i].points.size());
  }
  EXPECT_EQ(got.answers.back().code, grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_FALSE(got.answers.back().response.has_value());
}

}  // namespace
}  // namespace glimpse::server

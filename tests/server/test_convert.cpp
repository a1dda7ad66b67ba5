// Request -> core conversion and validation, the one error mapping, progress percentages, config.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "proto/wire/clouds.h"
#include "proto/wire/errors.h"
#include "proto/wire/methods.h"
#include "proto/wire/model_names.h"
#include "proto/wire/train_params.h"
#include "server/config.h"
#include "server/convert.h"
#include "server/log.h"
#include "server/train.h"

namespace glimpse::server {
namespace {

v1::PointCloud Packed(const Points& points) {
  v1::PointCloud msg;
  msg.set_xyz(wire::PackPoints(points));
  return msg;
}

TEST(CloudFromProto, EmptyCloudIsValidAndEmpty) {
  auto cloud = wire::CloudFromProto(v1::PointCloud(), 10);
  ASSERT_TRUE(cloud.ok());
  EXPECT_TRUE(cloud->points.empty());
  EXPECT_FALSE(cloud->sensor);
}

TEST(CloudFromProto, RoundTripsPointsAndSensorExactly) {
  Cloud in;
  in.points = {Vec3(1, 2, 3), Vec3(-0.5f, 1e-7f, 1e6f), Vec3(0, -0.0f, -123.456f)};  // 1e6 m: the largest allowed
  in.sensor = Vec3(0.1f, 0.2f, -3);
  auto out = wire::CloudFromProto(wire::CloudToProto(in), 10);
  ASSERT_TRUE(out.ok());
  ASSERT_EQ(out->points.size(), 3u);
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(out->points[i], in.points[i]);
  ASSERT_TRUE(out->sensor);
  EXPECT_EQ(*out->sensor, *in.sensor);
}

TEST(CloudFromProto, BytesAreLittleEndianFloat32Triples) {
  v1::PointCloud msg;
  const unsigned char one_two_three[] = {0, 0, 0x80, 0x3f, 0, 0, 0, 0x40, 0, 0, 0x40, 0x40};  // 1.f, 2.f, 3.f
  msg.set_xyz(std::string(reinterpret_cast<const char*>(one_two_three), 12));
  auto cloud = wire::CloudFromProto(msg, 10);
  ASSERT_TRUE(cloud.ok());
  EXPECT_EQ(cloud->points.at(0), Vec3(1, 2, 3));
  EXPECT_EQ(wire::PackPoints({Vec3(1, 2, 3)}), msg.xyz());
}

TEST(CloudFromProto, LengthNotAMultipleOf12IsInvalid) {
  for (size_t bytes : {1u, 11u, 13u, 25u}) {
    v1::PointCloud msg;
    msg.set_xyz(std::string(bytes, '\0'));
    auto cloud = wire::CloudFromProto(msg, 100);
    ASSERT_FALSE(cloud.ok());
    EXPECT_EQ(cloud.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(cloud.error().message.find("multiple of 12"), std::string::npos);
  }
}

TEST(CloudFromProto, NanOrInfNamesTheFirstBadPoint) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (float bad : {nan, inf, -inf}) {
    Points points(10, Vec3(1, 1, 1));
    points[7] = Vec3(0, bad, 0);
    points[9] = Vec3(bad, 0, 0);
    auto cloud = wire::CloudFromProto(Packed(points), 100);
    ASSERT_FALSE(cloud.ok());
    EXPECT_EQ(cloud.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(cloud.error().message.find("point 7 "), std::string::npos) << cloud.error().message;
  }
}

// PCL's kd-tree asserts (flann middleSplit) on a cloud at 3e38 m, and core's voxel keys overflow long
// before that: the service refuses such coordinates.
TEST(CloudFromProto, CoordinatesBeyondAMillionMetresAreInvalid) {
  for (float huge : {3e38f, -1e30f, 1.0001e6f}) {
    Points points(10, Vec3(1, 1, 1));
    points[3] = Vec3(0, 0, huge);
    auto cloud = wire::CloudFromProto(Packed(points), 100);
    ASSERT_FALSE(cloud.ok());
    EXPECT_EQ(cloud.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(cloud.error().message.find("point 3 has a coordinate beyond"), std::string::npos) << cloud.error().message;
  }
  Points edge(10, Vec3(1e6f, -1e6f, 0));
  EXPECT_TRUE(wire::CloudFromProto(Packed(edge), 100).ok());
  v1::PointCloud far = Packed(edge);
  far.mutable_sensor()->set_x(2e6f);
  EXPECT_EQ(wire::CloudFromProto(far, 100).error().code, ErrorCode::kInvalidArgument);
}

TEST(CloudFromProto, TooManyPointsIsResourceExhausted) {
  EXPECT_TRUE(wire::CloudFromProto(Packed(Points(5, Vec3::Zero())), 5).ok());
  auto cloud = wire::CloudFromProto(Packed(Points(6, Vec3::Zero())), 5);
  ASSERT_FALSE(cloud.ok());
  EXPECT_EQ(cloud.error().code, ErrorCode::kResourceExhausted);
}

TEST(CloudFromProto, NormalsMustMatchAndBeFinite) {
  v1::PointCloud msg = Packed({Vec3(1, 0, 0), Vec3(0, 1, 0)});
  msg.set_normals(wire::PackPoints({Vec3(0, 0, 1)}));
  EXPECT_EQ(wire::CloudFromProto(msg, 10).error().code, ErrorCode::kInvalidArgument);
  msg.set_normals(wire::PackPoints({Vec3(0, 0, 1), Vec3(0, std::nanf(""), 1)}));
  auto bad = wire::CloudFromProto(msg, 10);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("normals: point 1"), std::string::npos) << bad.error().message;
  msg.set_normals(wire::PackPoints({Vec3(0, 0, 1), Vec3(0, 0, 1)}));
  EXPECT_TRUE(wire::CloudFromProto(msg, 10).ok());
}

TEST(CloudFromProto, NonFiniteSensorIsInvalid) {
  v1::PointCloud msg = Packed({Vec3(1, 0, 0)});
  msg.mutable_sensor()->set_x(std::numeric_limits<float>::infinity());
  EXPECT_EQ(wire::CloudFromProto(msg, 10).error().code, ErrorCode::kInvalidArgument);
}

TEST(MethodFromProto, MapsEveryMethodAndRejectsUnknownValues) {
  EXPECT_FALSE(wire::MethodFromProto(v1::METHOD_UNSPECIFIED)->has_value());
  for (MethodId m : kAllMethods) {
    auto back = wire::MethodFromProto(wire::MethodToProto(m));
    ASSERT_TRUE(back.ok());
    EXPECT_EQ(**back, m);
  }
  EXPECT_EQ(wire::MethodToProto(MethodId::kBoK), v1::METHOD_BOK);
  EXPECT_EQ(wire::MethodToProto(MethodId::kFusion), v1::METHOD_FUSION);
  EXPECT_EQ(wire::MethodFromProto(42).error().code, ErrorCode::kInvalidArgument);
  EXPECT_EQ(wire::MethodFromProto(-1).error().code, ErrorCode::kInvalidArgument);
}

TEST(ValidateModelName, AcceptsTheDocumentedAlphabetOnly) {
  EXPECT_TRUE(wire::ValidateModelName("chairs-v2.final_1").ok());
  EXPECT_TRUE(wire::ValidateModelName(std::string(128, 'a')).ok());
  EXPECT_FALSE(wire::ValidateModelName("").ok());
  EXPECT_FALSE(wire::ValidateModelName(std::string(129, 'a')).ok());
  EXPECT_FALSE(wire::ValidateModelName("a b").ok());
  EXPECT_FALSE(wire::ValidateModelName("a/b").ok());
  EXPECT_FALSE(wire::ValidateModelName("a@1").ok());
}

TEST(TrainSpecFromProto, ChecksMethodsAndParameterRanges) {
  v1::TrainHeader h;
  h.set_model_name("m");
  h.add_methods(v1::METHOD_BOK);
  h.add_methods(v1::METHOD_VFH);
  h.set_default_method(v1::METHOD_VFH);
  h.mutable_parameters()->set_support_radius_m(0.05);
  h.mutable_parameters()->set_bok_codebook_size(30);
  h.mutable_parameters()->set_decision(v1::DECISION_KIND_NEAREST_CENTRE);
  auto spec = wire::TrainSpecFromProto(h);
  ASSERT_TRUE(spec.ok()) << spec.error().message;
  EXPECT_EQ(spec->methods, (std::vector<MethodId>{MethodId::kBoK, MethodId::kVFH}));
  EXPECT_EQ(spec->default_method, MethodId::kVFH);
  EXPECT_EQ(spec->parameters.bok_codebook_size(), 30u);

  auto bad = [&](auto&& edit) {
    v1::TrainHeader copy = h;
    edit(copy);
    auto r = wire::TrainSpecFromProto(copy);
    return !r.ok() && r.error().code == ErrorCode::kInvalidArgument;
  };
  EXPECT_TRUE(bad([](v1::TrainHeader& c) { c.set_model_name(""); }));
  EXPECT_TRUE(bad([](v1::TrainHeader& c) { c.add_methods(v1::METHOD_UNSPECIFIED); }));
  EXPECT_TRUE(bad([](v1::TrainHeader& c) { c.add_methods(static_cast<v1::Method>(77)); }));
  EXPECT_TRUE(bad([](v1::TrainHeader& c) { c.set_default_method(v1::METHOD_ESF); }));  // not trained
  EXPECT_TRUE(bad([](v1::TrainHeader& c) { c.mutable_parameters()->set_support_radius_m(-1); }));
  EXPECT_TRUE(bad([](v1::TrainHeader& c) { c.mutable_parameters()->set_support_radius_m(NAN); }));
  EXPECT_TRUE(bad([](v1::TrainHeader& c) { c.mutable_parameters()->set_bok_codebook_size(0); }));
  EXPECT_TRUE(bad([](v1::TrainHeader& c) { c.mutable_parameters()->set_neighbours(0); }));
  EXPECT_TRUE(bad([](v1::TrainHeader& c) { c.mutable_parameters()->set_decision(static_cast<v1::DecisionKind>(9)); }));
  EXPECT_TRUE(bad([](v1::TrainHeader& c) { c.set_description(std::string(5000, 'd')); }));
}

TEST(TrainParams, EveryFieldGoesToCoreAndBack) {
  wire::TrainSpec spec;
  v1::TrainParameters& p = spec.parameters;
  p.set_support_radius_m(0.25);
  p.set_bok_codebook_size(11);
  p.set_bog_keypoint_clusters(12);
  p.set_bog_volume_clusters(13);
  p.set_bog_pca_dims(14);
  p.set_kgh_keypoint_clusters(15);
  p.set_kgh_distance_bins(16);
  p.set_decision(v1::DECISION_KIND_CENTRES);
  p.set_seed(19);
  p.set_centres_per_category(17);
  p.set_neighbours(18);
  p.set_normalise_histograms(false);
  p.set_filter_scans(false);
  auto params = wire::ToTrainParams(spec);
  ASSERT_TRUE(params.ok()) << params.error().message;
  EXPECT_EQ(params->bok_clusters, 11);
  EXPECT_EQ(params->kgh_distance_bins, 16);
  EXPECT_EQ(params->decision.centres_per_category, 17);
  EXPECT_EQ(params->decision.neighbours, 18);
  EXPECT_EQ(params->decision.kind, DecisionRule::kCentres);
  EXPECT_EQ(wire::FromTrainParams(*params).DebugString(), p.DebugString());

  p.set_neighbours(3'000'000'000u);  // beyond int
  auto large = wire::ToTrainParams(spec);
  ASSERT_FALSE(large.ok());
  EXPECT_EQ(large.error().message, "neighbours is too large");
}

// Each score keeps its raw value under `score`, and carries its calibrated probability only when the
// answer has one per category (a model's default method); a stream's raw_scores never do.
TEST(ToProto, ScoresCarryTheirProbabilitiesOnlyWhenCalibrated) {
  Classification c;
  c.categories = {"chair", "table"};
  c.scores = {0.6, 0.4};
  c.winner = 0;
  v1::ClassifyResponse plain;
  ToProto(c, &plain);
  ASSERT_EQ(plain.scores_size(), 2);
  for (const v1::CategoryScore& s : plain.scores()) EXPECT_FALSE(s.has_probability());
  c.probabilities = {0.9, 0.1};
  v1::ClassifyResponse calibrated;
  ToProto(c, &calibrated);
  EXPECT_DOUBLE_EQ(calibrated.scores(0).score(), 0.6);
  EXPECT_DOUBLE_EQ(calibrated.scores(0).probability(), 0.9);
  EXPECT_DOUBLE_EQ(calibrated.scores(1).probability(), 0.1);
  StreamDecision d;
  d.categories = c.categories;
  d.scores = c.scores;
  d.raw_scores = {0.7, 0.3};
  d.probabilities = {0.95, 0.05};
  d.winner = 0;
  v1::Decision decision;
  ToProto(d, &decision);
  EXPECT_DOUBLE_EQ(decision.scores(1).probability(), 0.05);
  ASSERT_EQ(decision.raw_scores_size(), 2);
  EXPECT_FALSE(decision.raw_scores(0).has_probability());
}

TEST(ToGrpcStatus, MapsEveryErrorCode) {
  using grpc::StatusCode;
  const std::pair<ErrorCode, StatusCode> table[] = {
      {ErrorCode::kInvalidArgument, StatusCode::INVALID_ARGUMENT},
      {ErrorCode::kNotFound, StatusCode::NOT_FOUND},
      {ErrorCode::kResourceExhausted, StatusCode::RESOURCE_EXHAUSTED},
      {ErrorCode::kFailedPrecondition, StatusCode::FAILED_PRECONDITION},
      {ErrorCode::kDataLoss, StatusCode::DATA_LOSS},
      {ErrorCode::kCancelled, StatusCode::CANCELLED},
      {ErrorCode::kInternal, StatusCode::INTERNAL},
  };
  for (auto [code, expected] : table) {
    grpc::Status s = wire::ToGrpcStatus(Error{code, "why"});
    EXPECT_EQ(s.error_code(), expected);
    EXPECT_EQ(s.error_message(), "why");
  }
  EXPECT_EQ(wire::ToGrpcStatus(cancelled("late"), true).error_code(), StatusCode::DEADLINE_EXCEEDED);
  EXPECT_EQ(wire::ToGrpcStatus(invalid_argument("x"), true).error_code(), StatusCode::INVALID_ARGUMENT);
}

TEST(TrainPercent, SecondsLeftExtrapolateTheShareDone) {
  EXPECT_EQ(SecondsLeft(0, 10), 0);   // nothing done yet: no estimate
  EXPECT_EQ(SecondsLeft(4.9, 10), 0);
  EXPECT_DOUBLE_EQ(SecondsLeft(25, 30), 90);  // a quarter in 30 s: 90 s to go
  EXPECT_DOUBLE_EQ(SecondsLeft(50, 30), 30);
  EXPECT_EQ(SecondsLeft(100, 30), 0);
  EXPECT_EQ(SecondsLeft(50, -1), 0);  // a clock that went back says nothing
}

TEST(TrainPercent, IsMonotonicOverTheStagesInOrder) {
  double last = 0;
  for (const char* stage : {"features", "codebooks", "centres", "calibration", "novelty", "storing"}) {
    for (size_t done = 0; done <= 4; ++done) {
      double p = TrainPercent(stage, done, 4);
      EXPECT_GE(p, last) << stage << " " << done;
      EXPECT_LT(p, 100);
      last = p;
    }
  }
  EXPECT_EQ(TrainPercent("done", 1, 1), 100);
  EXPECT_EQ(TrainPercent("features", 3, 0), 0);  // no total: start of the stage
  EXPECT_LT(TrainPercent("mystery", 1, 2), 0);
}

TEST(TrainPercent, AGrownModelsFewFeaturesTakeTheirShareAndTheStagesTheRest) {
  const double share = 5;  // a grown model: the features of a few added clouds
  EXPECT_DOUBLE_EQ(TrainPercent("features", 4, 4, share), share);
  EXPECT_DOUBLE_EQ(TrainPercent("codebooks", 0, 3, share), share);
  EXPECT_NEAR(TrainPercent("calibration", 0, 4, share), share + (79.0 - 65) * (100 - share) / 35, 1e-9);
  EXPECT_EQ(TrainPercent("done", 1, 1, share), 100);
  double last = 0;
  for (const char* stage : {"features", "codebooks", "centres", "calibration", "novelty", "storing"})
    for (size_t done = 0; done <= 4; ++done) {
      const double p = TrainPercent(stage, done, 4, share);
      EXPECT_GE(p, last) << stage << " " << done;
      last = p;
    }
  EXPECT_DOUBLE_EQ(TrainPercent("centres", 2, 4), TrainPercent("centres", 2, 4, kFeaturesPercent));
}

TEST(AddTrainRequest, HeaderFirstOnceThenLabelledCloudsWithinLimits) {
  Limits limits;
  limits.max_train_clouds = 2;
  limits.max_train_points = 25;
  TrainInput input;
  v1::TrainRequest cloud;
  cloud.mutable_cloud()->set_category("box");
  *cloud.mutable_cloud()->mutable_cloud() = Packed(Points(10, Vec3(1, 2, 3)));
  EXPECT_EQ(AddTrainRequest(cloud, limits, input).error().code, ErrorCode::kInvalidArgument);  // no header
  EXPECT_EQ(AddTrainRequest(v1::TrainRequest(), limits, input).error().code, ErrorCode::kInvalidArgument);
  v1::TrainRequest header;
  header.mutable_header()->set_model_name("m");
  ASSERT_TRUE(AddTrainRequest(header, limits, input).ok());
  EXPECT_EQ(AddTrainRequest(header, limits, input).error().code, ErrorCode::kInvalidArgument);  // twice
  ASSERT_TRUE(AddTrainRequest(cloud, limits, input).ok());
  EXPECT_EQ(input.clouds.at(0).object_id, "#0");  // no id: its own object
  v1::TrainRequest unlabelled = cloud;
  unlabelled.mutable_cloud()->clear_category();
  EXPECT_EQ(AddTrainRequest(unlabelled, limits, input).error().code, ErrorCode::kInvalidArgument);
  v1::TrainRequest big = cloud;
  *big.mutable_cloud()->mutable_cloud() = Packed(Points(16, Vec3(1, 2, 3)));
  EXPECT_EQ(AddTrainRequest(big, limits, input).error().code, ErrorCode::kResourceExhausted);  // 26 points
  ASSERT_TRUE(AddTrainRequest(cloud, limits, input).ok());
  EXPECT_EQ(AddTrainRequest(cloud, limits, input).error().code, ErrorCode::kResourceExhausted);  // 3 clouds
  EXPECT_TRUE(CheckTrainInput(input).ok());
  EXPECT_EQ(CheckTrainInput(TrainInput{}).error().code, ErrorCode::kInvalidArgument);
}

// ---------------------------------------------------------------------------------------------
// Config

EnvFn Env(std::map<std::string, std::string> vars) {
  return [vars](const std::string& k) -> std::optional<std::string> {
    auto it = vars.find(k);
    return it == vars.end() ? std::nullopt : std::optional<std::string>(it->second);
  };
}

TEST(Config, DefaultsMatchTheDocumentation) {
  auto c = ParseConfig({}, Env({}));
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->address, "0.0.0.0:50051");
  EXPECT_EQ(c->db_path, "./var/glimpse.db");
  EXPECT_EQ(c->metrics_port, 9464);
  EXPECT_EQ(c->limits.max_points_per_cloud, 1'000'000u);
  EXPECT_FALSE(c->help);
  EXPECT_EQ(c->limits.max_batch_clouds, 256u);
  EXPECT_EQ(c->request_threads, 0);
  // Threads follow the CPUs the process may use, not the node's cores.
  EXPECT_EQ(EffectiveThreads(*c, 2), int(c->limits.max_concurrent_streams) + 4);
  EXPECT_EQ(EffectiveThreads(*c, 8), int(c->limits.max_concurrent_streams) + 16);
  EXPECT_EQ(RequestThreads(*c, 2), 2);
  EXPECT_EQ(CompletionQueues(64), 4);
  EXPECT_EQ(CompletionQueues(1), 1);
}

TEST(Config, RequestThreadsFlagWinsOverTheUsableCpus) {
  auto c = ParseConfig({"--request-threads=3", "--threads", "20", "--max-batch-clouds=8"}, Env({}));
  ASSERT_TRUE(c.ok()) << c.error().message;
  EXPECT_EQ(RequestThreads(*c, 64), 3);
  EXPECT_EQ(EffectiveThreads(*c, 64), 20);
  EXPECT_EQ(c->limits.max_batch_clouds, 8u);
  EXPECT_FALSE(ParseConfig({"--request-threads=-1"}, Env({})).ok());
  EXPECT_FALSE(ParseConfig({"--max-batch-clouds=0"}, Env({})).ok());
  auto env = ParseConfig({}, Env({{"GLIMPSE_REQUEST_THREADS", "5"}}));
  ASSERT_TRUE(env.ok());
  EXPECT_EQ(env->request_threads, 5);
}

TEST(Config, EnvironmentThenFlagsWin) {
  auto c = ParseConfig({"--metrics-port=0", "--db", "/tmp/x.db", "--max-stream-seconds=30"},
                       Env({{"GLIMPSE_METRICS_PORT", "9999"}, {"GLIMPSE_ADDRESS", "127.0.0.1:1"},
                            {"GLIMPSE_MAX_POINTS", "500"}, {"GLIMPSE_MAX_STREAMS", "3"}}));
  ASSERT_TRUE(c.ok()) << c.error().message;
  EXPECT_EQ(c->metrics_port, 0);
  EXPECT_EQ(c->address, "127.0.0.1:1");
  EXPECT_EQ(c->db_path, "/tmp/x.db");
  EXPECT_EQ(c->limits.max_points_per_cloud, 500u);
  EXPECT_EQ(c->limits.max_concurrent_streams, 3u);
  EXPECT_EQ(c->limits.max_stream_duration, std::chrono::seconds(30));
}

TEST(Config, BadInputNamesTheFlagOrVariable) {
  auto unknown = ParseConfig({"--nope=1"}, Env({}));
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().message.find("--nope"), std::string::npos);
  auto number = ParseConfig({"--threads=many"}, Env({}));
  ASSERT_FALSE(number.ok());
  EXPECT_NE(number.error().message.find("--threads"), std::string::npos);
  auto env = ParseConfig({}, Env({{"GLIMPSE_MAX_POINTS", "-5"}}));
  ASSERT_FALSE(env.ok());
  EXPECT_NE(env.error().message.find("GLIMPSE_MAX_POINTS"), std::string::npos);
  EXPECT_FALSE(ParseConfig({"--db"}, Env({})).ok());  // missing value
  EXPECT_FALSE(ParseConfig({"stray"}, Env({})).ok());
  EXPECT_FALSE(ParseConfig({"--max-streams=0"}, Env({})).ok());
}

TEST(Config, HelpListsEveryFlagAndVariable) {
  auto c = ParseConfig({"--help"}, Env({}));
  ASSERT_TRUE(c.ok());
  EXPECT_TRUE(c->help);
  const std::string usage = Usage();
  for (const char* s : {"--address", "GLIMPSE_ADDRESS", "--db", "--metrics-port", "--threads", "--max-message-bytes",
                        "--max-points", "--max-streams", "--max-stream-seconds", "--max-train-clouds", "SIGTERM"})
    EXPECT_NE(usage.find(s), std::string::npos) << s;
}

TEST(Log, OneQuotedLogfmtLine) {
  RequestLog e;
  e.rpc = "Classify";
  e.model = "chairs@3";
  e.method = "bok";
  e.points = 1234;
  e.latency_ms = 1.5;
  e.code = "INVALID_ARGUMENT";
  e.message = "xyz: point 7 is \"not\" finite\nsecond line";
  const std::string line = FormatLogLine(e);
  EXPECT_EQ(line.find('\n'), std::string::npos);
  EXPECT_NE(line.find(" rpc=Classify model=chairs@3 method=bok points=1234 latency_ms=1.500 code=INVALID_ARGUMENT"),
            std::string::npos) << line;
  EXPECT_NE(line.find(R"(error="xyz: point 7 is \"not\" finite second line")"), std::string::npos) << line;
  EXPECT_NE(line.find("level=warn"), std::string::npos);
}

}  // namespace
}  // namespace glimpse::server

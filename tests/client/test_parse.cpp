#include <gtest/gtest.h>

#include "client/parse.h"
#include "proto/wire/errors.h"
#include "proto/wire/methods.h"

namespace glimpse::client {
namespace {

TEST(ParseModelRef, NameAloneMeansDefaultVersion) {
  auto ref = ParseModelRef("zoo");
  ASSERT_TRUE(ref.ok());
  EXPECT_EQ(ref->name(), "zoo");
  EXPECT_EQ(ref->version(), 0u);
  EXPECT_EQ(FormatModelRef(*ref), "zoo");
}

TEST(ParseModelRef, NameAndVersion) {
  auto ref = ParseModelRef("shrec-07.v2_a:12");
  ASSERT_TRUE(ref.ok());
  EXPECT_EQ(ref->name(), "shrec-07.v2_a");
  EXPECT_EQ(ref->version(), 12u);
  EXPECT_EQ(FormatModelRef(*ref), "shrec-07.v2_a:12");
  auto latest = ParseModelRef("zoo:latest", /*allow_latest=*/true);
  ASSERT_TRUE(latest.ok());
  EXPECT_EQ(latest->version(), 0u);
}

// "latest" as version 0 would ask for the default (perhaps pinned), and `models delete NAME:latest`
// would delete every version: only set-default takes it.
TEST(ParseModelRef, LatestOnlyWhereAllowed) {
  auto refused = ParseModelRef("zoo:latest");
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("set-default"), std::string::npos) << refused.error().message;
}

TEST(ParseModelRef, RejectsBadNamesAndVersions) {
  for (const char* bad : {"", ":3", "a b", "zoo:", "zoo:0", "zoo:-1", "zoo:1x", "zoo:99999999999", "zo/o",
                          "zoo:1:2"})
    EXPECT_FALSE(ParseModelRef(bad).ok()) << bad;
  EXPECT_TRUE(ParseModelRef(std::string(128, 'a')).ok());
  EXPECT_FALSE(ParseModelRef(std::string(129, 'a')).ok());
}

TEST(ParseMethod, NamesAreCaseInsensitiveAndErrorsListValidOnes) {
  EXPECT_EQ(*wire::ParseMethod("bok"), v1::METHOD_BOK);
  EXPECT_EQ(*wire::ParseMethod(" FUSION "), v1::METHOD_FUSION);
  auto bad = wire::ParseMethod("svm");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("bok, bog, kgh, vfh, esf, ush, size, fusion"), std::string::npos);
  for (const std::string& name : wire::MethodNames()) EXPECT_EQ(wire::MethodName(*wire::ParseMethod(name)), name);
  EXPECT_EQ(wire::MethodName(v1::METHOD_UNSPECIFIED), "default");
}

TEST(ParseMethodList, CommaSeparatedWithoutDuplicates) {
  auto list = ParseMethodList("bok, bog,esf");
  ASSERT_TRUE(list.ok());
  EXPECT_EQ(*list, (std::vector<v1::Method>{v1::METHOD_BOK, v1::METHOD_BOG, v1::METHOD_ESF}));
  EXPECT_TRUE(ParseMethodList("")->empty());
  EXPECT_FALSE(ParseMethodList("bok,bok").ok());
  EXPECT_FALSE(ParseMethodList("bok,").ok());
  EXPECT_FALSE(ParseMethodList("bok,nope").ok());
}

TEST(ParseSensor, ThreeFiniteNumbers) {
  auto origin = ParseSensor("0,0,0");
  ASSERT_TRUE(origin.ok());
  EXPECT_EQ(*origin, Vec3::Zero());
  auto p = ParseSensor(" 1.5, -2 ,3e-1");
  ASSERT_TRUE(p.ok());
  EXPECT_EQ(*p, Vec3(1.5f, -2.0f, 0.3f));
  for (const char* bad : {"", "0,0", "0,0,0,0", "a,0,0", "0,,0", "nan,0,0", "inf,0,0", "1e9,0,0", "0 0 0"})
    EXPECT_FALSE(ParseSensor(bad).ok()) << bad;
  EXPECT_NE(ParseSensor("x").error().message.find("X,Y,Z"), std::string::npos);
}

TEST(ParseTrackTarget, NearestAPointOrABox) {
  auto nearest = ParseTrackTarget(" nearest ");
  ASSERT_TRUE(nearest.ok());
  EXPECT_TRUE(nearest->nearest_axis());
  auto point = ParseTrackTarget("0.5,-1,0.25");
  ASSERT_TRUE(point.ok());
  ASSERT_EQ(point->target_case(), v1::TrackTarget::kPoint);
  EXPECT_EQ(point->point().y(), -1.f);
  auto box = ParseTrackTarget("0,0,0, 1,2,0.5");
  ASSERT_TRUE(box.ok());
  ASSERT_EQ(box->target_case(), v1::TrackTarget::kBox);
  EXPECT_EQ(box->box().max().y(), 2.f);
  EXPECT_EQ(box->box().min().x(), 0.f);
  for (const char* bad : {"", "near", "1,2", "1,2,3,4", "1,2,3,4,5,6,7", "nan,0,0", "1,,2", "1,1,1,0,0,0"})
    EXPECT_FALSE(ParseTrackTarget(bad).ok()) << bad;
  EXPECT_NE(ParseTrackTarget("1,1,1,0,0,0").error().message.find("minimum"), std::string::npos);
}

TEST(ParseFieldOfView, FullDegreesWidthByHeightEachInsideZeroTo180) {
  auto kinect = ParseFieldOfView("57x43");
  ASSERT_TRUE(kinect.ok());
  EXPECT_EQ(kinect->h_deg, 57.f);
  EXPECT_EQ(kinect->v_deg, 43.f);
  auto spaced = ParseFieldOfView(" 87.5 X 58 ");
  ASSERT_TRUE(spaced.ok());
  EXPECT_EQ(spaced->h_deg, 87.5f);
  for (const char* bad : {"", "57", "57x", "x43", "0x43", "57x180", "-57x43", "57x43x1", "ax43", "nanx43"})
    EXPECT_FALSE(ParseFieldOfView(bad).ok()) << bad;
  EXPECT_NE(ParseFieldOfView("57").error().message.find("HxV"), std::string::npos);
}

TEST(ParseUpChoice, AnAxisOrTheFloorWhereAllowed) {
  auto axis = ParseUpChoice("-y", true);
  ASSERT_TRUE(axis.ok());
  EXPECT_FALSE(axis->floor);
  ASSERT_TRUE(axis->axis.has_value());
  EXPECT_TRUE(axis->axis->isApprox(Vec3(0, -1, 0)));
  auto floor = ParseUpChoice(" floor ", true);
  ASSERT_TRUE(floor.ok());
  EXPECT_TRUE(floor->floor);
  EXPECT_FALSE(floor->axis.has_value());
  auto refused = ParseUpChoice("floor", false);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("single cloud file"), std::string::npos) << refused.error().message;
  EXPECT_FALSE(ParseUpChoice("sideways", true).ok());
}

TEST(StatusCodeName, MatchesGrpcNames) {
  EXPECT_STREQ(wire::StatusCodeName(grpc::StatusCode::NOT_FOUND), "NOT_FOUND");
  EXPECT_STREQ(wire::StatusCodeName(grpc::StatusCode::DEADLINE_EXCEEDED), "DEADLINE_EXCEEDED");
  EXPECT_STREQ(wire::StatusCodeName(grpc::StatusCode::UNAVAILABLE), "UNAVAILABLE");
  EXPECT_STREQ(wire::StatusCodeName(grpc::StatusCode::OK), "OK");
}

}  // namespace
}  // namespace glimpse::client

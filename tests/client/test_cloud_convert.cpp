// The cloud codec as the client uses it (proto/wire/clouds.h): packed little-endian float32, chunks of a
// scan packed into a reused message, decoding as it is; and the non-finite points a file may hold.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "client/inputs.h"
#include "proto/wire/clouds.h"

namespace glimpse::client {
namespace {

TEST(CloudConvert, EmptyCloudGivesEmptyBytesAndNoSensor) {
  const v1::PointCloud proto = wire::CloudToProto(Cloud{});
  EXPECT_TRUE(proto.xyz().empty());
  EXPECT_FALSE(proto.has_sensor());
  auto back = wire::DecodeCloud(proto);
  ASSERT_TRUE(back.ok());
  EXPECT_TRUE(back->points.empty());
  EXPECT_FALSE(back->sensor.has_value());
}

TEST(CloudConvert, PacksLittleEndianFloat32Triples) {
  Cloud cloud;
  cloud.points = {Vec3(1.0f, -2.0f, 0.5f)};
  const std::string xyz = wire::CloudToProto(cloud).xyz();
  ASSERT_EQ(xyz.size(), 12u);
  // 1.0f = 0x3f800000, -2.0f = 0xc0000000, 0.5f = 0x3f000000, least significant byte first.
  const unsigned char expected[12] = {0, 0, 0x80, 0x3f, 0, 0, 0, 0xc0, 0, 0, 0, 0x3f};
  for (int i = 0; i < 12; ++i) EXPECT_EQ(static_cast<unsigned char>(xyz[i]), expected[i]) << "byte " << i;
}

TEST(CloudConvert, RoundTripIsBitExactWithSensor) {
  Cloud cloud;
  cloud.points = {Vec3(0.1f, 0.2f, 0.3f), Vec3(-1e-20f, 3.4e38f, -0.0f), Vec3(7, 8, 9)};
  cloud.sensor = Vec3(0.0f, -2.5f, 1.25f);
  auto back = wire::DecodeCloud(wire::CloudToProto(cloud));
  ASSERT_TRUE(back.ok());
  ASSERT_EQ(back->points.size(), cloud.points.size());
  for (size_t i = 0; i < cloud.points.size(); ++i)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(std::signbit(back->points[i][k]), std::signbit(cloud.points[i][k]));
  for (size_t i = 0; i < cloud.points.size(); ++i) EXPECT_EQ(back->points[i], cloud.points[i]);
  ASSERT_TRUE(back->sensor.has_value());
  EXPECT_EQ(*back->sensor, *cloud.sensor);
}

TEST(CloudConvert, RangePacksOnlyThatChunkAndClampsBounds) {
  Cloud cloud;
  for (int i = 0; i < 10; ++i) cloud.points.push_back(Vec3(float(i), 0, 0));
  v1::PointCloud proto;
  wire::CloudToProto(cloud, 3, 6, &proto);
  auto chunk = wire::DecodeCloud(proto);
  ASSERT_TRUE(chunk.ok());
  ASSERT_EQ(chunk->points.size(), 3u);
  EXPECT_EQ(chunk->points[0].x(), 3.0f);
  EXPECT_EQ(chunk->points[2].x(), 5.0f);
  wire::CloudToProto(cloud, 8, 100, &proto);  // reuse: the previous content is replaced
  EXPECT_EQ(proto.xyz().size(), 24u);
  wire::CloudToProto(cloud, 20, 30, &proto);
  EXPECT_TRUE(proto.xyz().empty());
}

TEST(CloudConvert, ReusedMessageLosesAnOldSensor) {
  Cloud with;
  with.points = {Vec3(1, 2, 3)};
  with.sensor = Vec3(0, 0, 1);
  v1::PointCloud proto;
  wire::CloudToProto(with, &proto);
  wire::CloudToProto(Cloud{with.points, std::nullopt, {}}, &proto);
  EXPECT_FALSE(proto.has_sensor());
}

TEST(CloudConvert, TheCamerasFrameTravelsWithTheCloudAndAReusedMessageLosesIt) {
  Cloud cloud;
  cloud.points = {Vec3(1, 2, 3)};
  cloud.sensor = Vec3(0, 0, 1);
  cloud.frame = CameraFrame{Vec3(1, 0, 0), Vec3(0, 0, 1), 57.f, 43.f};
  v1::PointCloud proto;
  wire::CloudToProto(cloud, &proto);
  auto back = wire::CloudFromProto(proto, 10);
  ASSERT_TRUE(back.ok()) << back.error().message;
  ASSERT_TRUE(back->frame.has_value());
  EXPECT_TRUE(*back->frame == *cloud.frame);
  wire::CloudToProto(Cloud{cloud.points, cloud.sensor, {}}, &proto);
  EXPECT_FALSE(proto.has_frame());
}

TEST(CloudConvert, AFrameItsEdgesCannotBeFoundFromIsInvalidArgumentNamingTheField) {
  const Cloud good{{Vec3(1, 2, 3)}, Vec3(0, 0, 1), CameraFrame{Vec3(1, 0, 0), Vec3(0, 0, 1), 57.f, 43.f}};
  auto refused = [&](auto&& spoil, const std::string& field) {
    Cloud c = good;
    spoil(c);
    auto back = wire::CloudFromProto(wire::CloudToProto(c), 10);
    ASSERT_FALSE(back.ok()) << field;
    EXPECT_EQ(back.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(back.error().message.find(field), std::string::npos) << back.error().message;
  };
  refused([](Cloud& c) { c.sensor.reset(); }, "sensor");
  refused([](Cloud& c) { c.frame->axis = Vec3::Zero(); }, "frame.axis");
  refused([](Cloud& c) { c.frame->up = Vec3(2, 0, 0); }, "frame.image_up");
  refused([](Cloud& c) { c.frame->fov_h_deg = 0; }, "fields of view");
  refused([](Cloud& c) { c.frame->fov_v_deg = 180; }, "fields of view");
  refused([](Cloud& c) { c.frame->up.x() = std::numeric_limits<float>::quiet_NaN(); }, "frame.image_up");
}

TEST(CloudConvert, RejectsBytesNotAMultipleOfTwelve) {
  v1::PointCloud proto;
  proto.set_xyz(std::string(13, '\0'));
  auto cloud = wire::DecodeCloud(proto);
  ASSERT_FALSE(cloud.ok());
  EXPECT_EQ(cloud.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(cloud.error().message.find("13"), std::string::npos);
}

TEST(CloudConvert, RemoveNonFiniteDropsNanAndInfPoints) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  Cloud cloud;
  cloud.points = {Vec3(1, 1, 1), Vec3(nan, 0, 0), Vec3(2, 2, 2), Vec3(0, -inf, 0), Vec3(0, 0, nan)};
  EXPECT_EQ(RemoveNonFinite(cloud), 3u);
  ASSERT_EQ(cloud.points.size(), 2u);
  EXPECT_EQ(cloud.points[1], Vec3(2, 2, 2));
  Cloud empty;
  EXPECT_EQ(RemoveNonFinite(empty), 0u);
}

}  // namespace
}  // namespace glimpse::client

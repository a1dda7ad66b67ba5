// The gRPC server as main.cc builds it, on a real loopback port over a temporary SQLite file: health
// checking, reflection, message size limits, two servers sharing one store, graceful shutdown.
// Health and reflection are called with hand-encoded protobuf bytes (their .proto files are not
// installed by Debian's gRPC), decoded with protobuf's UnknownFieldSet.
#include <gmock/gmock.h>
#include <google/protobuf/unknown_field_set.h>
#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>

#include <future>

#include "common/temp_dir.h"
#include "fakes.h"
#include "server/server.h"

namespace glimpse::server {
namespace {

using ::testing::HasSubstr;
using testing::SpiralCloud;
using glimpse::testing::TempDir;

// ---- protobuf wire helpers ------------------------------------------------------------------
std::string StringField(int field, const std::string& value) {
  std::string out(1, static_cast<char>((field << 3) | 2));
  out.push_back(static_cast<char>(value.size()));  // values here are < 128 bytes
  return out + value;
}

grpc::ByteBuffer ToBuffer(const std::string& bytes) {
  grpc::Slice slice(bytes);
  return grpc::ByteBuffer(&slice, 1);
}

std::string FromBuffer(const grpc::ByteBuffer& buffer) {
  grpc::Slice slice;
  if (!buffer.DumpToSingleSlice(&slice).ok()) return {};
  return std::string(reinterpret_cast<const char*>(slice.begin()), slice.size());
}

struct Field {
  int number = 0;
  uint64_t varint = 0;
  std::string bytes;  // length-delimited payload
};

std::vector<Field> Parse(const std::string& message) {
  google::protobuf::UnknownFieldSet set;
  EXPECT_TRUE(set.ParseFromString(message));
  std::vector<Field> fields;
  for (int i = 0; i < set.field_count(); ++i) {
    const auto& f = set.field(i);
    Field out;
    out.number = f.number();
    if (f.type() == google::protobuf::UnknownField::TYPE_VARINT) out.varint = f.varint();
    if (f.type() == google::protobuf::UnknownField::TYPE_LENGTH_DELIMITED) out.bytes = f.length_delimited();
    fields.push_back(out);
  }
  return fields;
}

// ---- a server on 127.0.0.1:<free port> ---------------------------------------------------------
struct LoopbackServer {
  explicit LoopbackServer(const std::string& db, Limits limits = {}) {
    auto opened = ModelStore::Open(db);
    if (!opened) throw std::runtime_error(opened.error().message);
    store = std::move(*opened);
    ServiceOptions o;
    o.store = store.get();
    o.engine = testing::FakeEngine(&behaviour);
    o.limits = limits;
    o.metrics = &metrics;
    o.log = [](const RequestLog&) {};
    service = std::make_unique<GlimpseService>(std::move(o));
    GrpcServerOptions g;
    g.address = "127.0.0.1:0";
    g.threads = 8;
    g.max_message_bytes = limits.max_message_bytes;
    auto started = StartGrpcServer(g, service.get());
    if (!started) throw std::runtime_error(started.error().message);
    running = std::move(*started);
    channel = grpc::CreateChannel("127.0.0.1:" + std::to_string(running.port), grpc::InsecureChannelCredentials());
    stub = v1::Glimpse::NewStub(channel);
  }
  ~LoopbackServer() {
    if (running.server) ShutdownGrpcServer(*running.server, std::chrono::seconds(2));
  }

  testing::FakeBehaviour behaviour;
  std::unique_ptr<ModelStore> store;
  Metrics metrics;
  std::unique_ptr<GlimpseService> service;
  RunningServer running;
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<v1::Glimpse::Stub> stub;
};

grpc::Status Train(v1::Glimpse::Stub& stub, const std::string& name, v1::TrainProgress* last) {
  grpc::ClientContext ctx;
  auto stream = stub.Train(&ctx);
  v1::TrainRequest header;
  header.mutable_header()->set_model_name(name);
  stream->Write(header);
  for (const char* category : {"box", "sphere", "cylinder"}) {
    for (int i = 0; i < 2; ++i) {
      v1::TrainRequest req;
      req.mutable_cloud()->set_category(category);
      *req.mutable_cloud()->mutable_cloud() = wire::CloudToProto(SpiralCloud(40 + i));
      stream->Write(req);
    }
  }
  stream->WritesDone();
  for (v1::TrainProgress p; stream->Read(&p);) *last = p;
  return stream->Finish();
}

// grpc.health.v1.Health/Check -> the ServingStatus enum value (1 SERVING, 2 NOT_SERVING), or the error.
grpc::Status HealthCheck(grpc::Channel& channel, const std::string& service, int* status) {
  grpc::GenericStub stub(std::shared_ptr<grpc::Channel>(&channel, [](grpc::Channel*) {}));
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
  grpc::ByteBuffer request = ToBuffer(service.empty() ? std::string() : StringField(1, service)), response;
  std::promise<grpc::Status> done;
  stub.UnaryCall(&ctx, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                 [&](grpc::Status s) { done.set_value(s); });
  grpc::Status s = done.get_future().get();
  if (s.ok()) {
    auto fields = Parse(FromBuffer(response));
    *status = fields.empty() ? 0 : static_cast<int>(fields[0].varint);  // field 1; UNKNOWN = 0 is omitted
  }
  return s;
}

TEST(E2E, HealthReportsServingForTheServerAndTheService) {
  TempDir db("e2e");
  LoopbackServer server(db.file("glimpse.db"));
  int status = -1;
  ASSERT_TRUE(HealthCheck(*server.channel, "", &status).ok());
  EXPECT_EQ(status, 1);
  ASSERT_TRUE(HealthCheck(*server.channel, "glimpse.v1.Glimpse", &status).ok());
  EXPECT_EQ(status, 1);
  EXPECT_EQ(HealthCheck(*server.channel, "no.such.Service", &status).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST(E2E, ReflectionListsTheGlimpseService) {
  TempDir db("e2e");
  LoopbackServer server(db.file("glimpse.db"));
  grpc::GenericStub stub(server.channel);
  grpc::CompletionQueue cq;
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
  void* tag = nullptr;
  bool ok = false;
  auto call = stub.PrepareCall(&ctx, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo", &cq);
  auto step = [&](void* expected) {
    EXPECT_TRUE(cq.Next(&tag, &ok));
    EXPECT_EQ(tag, expected);
    return ok;
  };
  call->StartCall(reinterpret_cast<void*>(1));
  ASSERT_TRUE(step(reinterpret_cast<void*>(1)));
  call->Write(ToBuffer(StringField(7, "")), reinterpret_cast<void*>(2));  // list_services
  ASSERT_TRUE(step(reinterpret_cast<void*>(2)));
  grpc::ByteBuffer reply;
  call->Read(&reply, reinterpret_cast<void*>(3));
  ASSERT_TRUE(step(reinterpret_cast<void*>(3)));
  call->WritesDone(reinterpret_cast<void*>(4));
  step(reinterpret_cast<void*>(4));
  grpc::Status status;
  call->Finish(&status, reinterpret_cast<void*>(5));
  step(reinterpret_cast<void*>(5));
  EXPECT_TRUE(status.ok()) << status.error_message();

  std::vector<std::string> services;
  for (const Field& f : Parse(FromBuffer(reply))) {
    if (f.number != 6) continue;  // list_services_response
    for (const Field& service : Parse(f.bytes))   // repeated ServiceResponse service = 1
      for (const Field& name : Parse(service.bytes))  // string name = 1
        if (name.number == 1) services.push_back(name.bytes);
  }
  EXPECT_THAT(services, ::testing::Contains("glimpse.v1.Glimpse"));
  EXPECT_THAT(services, ::testing::Contains("grpc.health.v1.Health"));
}

TEST(E2E, TrainClassifyAndStreamOverLoopback) {
  TempDir db("e2e");
  LoopbackServer server(db.file("glimpse.db"));
  v1::TrainProgress last;
  ASSERT_TRUE(Train(*server.stub, "shapes", &last).ok());
  EXPECT_EQ(last.model().version(), 1u);

  grpc::ClientContext ctx;
  v1::ClassifyRequest req;
  req.mutable_model()->set_name("shapes");
  *req.mutable_cloud() = wire::CloudToProto(SpiralCloud(31));
  v1::ClassifyResponse resp;
  ASSERT_TRUE(server.stub->Classify(&ctx, req, &resp).ok());
  EXPECT_EQ(resp.scores_size(), 3);
  EXPECT_EQ(resp.winner(), "cylinder");  // 31 % 3 = 1 in (box, cylinder, sphere)

  grpc::ClientContext sctx;
  auto stream = server.stub->StreamClassify(&sctx);
  v1::ScanChunk chunk;
  chunk.mutable_model()->set_name("shapes");
  *chunk.mutable_cloud() = wire::CloudToProto(SpiralCloud(10));
  v1::Decision d;
  ASSERT_TRUE(stream->Write(chunk));
  ASSERT_TRUE(stream->Read(&d));
  EXPECT_EQ(d.points(), 10u);
  stream->WritesDone();
  ASSERT_TRUE(stream->Read(&d));
  EXPECT_TRUE(d.final());
  EXPECT_FALSE(stream->Read(&d));
  EXPECT_TRUE(stream->Finish().ok());
}

TEST(E2E, OversizedMessageIsResourceExhausted) {
  TempDir db("e2e");
  Limits limits;
  limits.max_message_bytes = 64 * 1024;
  LoopbackServer server(db.file("glimpse.db"), limits);
  grpc::ClientContext ctx;
  v1::ClassifyRequest req;
  req.mutable_model()->set_name("m");
  *req.mutable_cloud() = wire::CloudToProto(SpiralCloud(10'000));  // 120 kB
  v1::ClassifyResponse resp;
  EXPECT_EQ(server.stub->Classify(&ctx, req, &resp).error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
}

TEST(E2E, TwoServersOnOneDatabaseServeEachOthersModels) {
  TempDir db("e2e");
  LoopbackServer a(db.file("glimpse.db"));
  LoopbackServer b(db.file("glimpse.db"));
  v1::TrainProgress last;
  ASSERT_TRUE(Train(*a.stub, "shared", &last).ok());
  {
    grpc::ClientContext ctx;
    v1::ClassifyRequest req;
    req.mutable_model()->set_name("shared");
    *req.mutable_cloud() = wire::CloudToProto(SpiralCloud(30));
    v1::ClassifyResponse resp;
    ASSERT_TRUE(b.stub->Classify(&ctx, req, &resp).ok());  // b never saw the Train call
    EXPECT_EQ(resp.model().version(), 1u);
  }
  ASSERT_TRUE(Train(*b.stub, "shared", &last).ok());
  EXPECT_EQ(last.model().version(), 2u);
  {
    grpc::ClientContext ctx;
    v1::GetModelRequest req;
    req.mutable_model()->set_name("shared");
    v1::ModelInfo info;
    ASSERT_TRUE(a.stub->GetModel(&ctx, req, &info).ok());
    EXPECT_EQ(info.version(), 2u);
  }
  {
    grpc::ClientContext ctx;
    v1::DeleteModelRequest req;
    req.set_name("shared");
    req.set_version(1);
    v1::DeleteModelResponse resp;
    ASSERT_TRUE(b.stub->DeleteModel(&ctx, req, &resp).ok());
  }
  {
    grpc::ClientContext ctx;
    v1::ClassifyRequest req;
    req.mutable_model()->set_name("shared");
    req.mutable_model()->set_version(1);
    *req.mutable_cloud() = wire::CloudToProto(SpiralCloud(30));
    v1::ClassifyResponse resp;
    EXPECT_EQ(a.stub->Classify(&ctx, req, &resp).error_code(), grpc::StatusCode::NOT_FOUND);
  }
}

TEST(E2E, ShutdownLetsAnInFlightStreamFinish) {
  TempDir db("e2e");
  LoopbackServer server(db.file("glimpse.db"));
  v1::TrainProgress last;
  ASSERT_TRUE(Train(*server.stub, "m", &last).ok());
  grpc::ClientContext ctx;
  auto stream = server.stub->StreamClassify(&ctx);
  v1::ScanChunk chunk;
  chunk.mutable_model()->set_name("m");
  *chunk.mutable_cloud() = wire::CloudToProto(SpiralCloud(10));
  v1::Decision d;
  ASSERT_TRUE(stream->Write(chunk));
  ASSERT_TRUE(stream->Read(&d));

  auto stopped = std::async(std::launch::async, [&] {
    ShutdownGrpcServer(*server.running.server, std::chrono::seconds(10));
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_EQ(stopped.wait_for(std::chrono::milliseconds(0)), std::future_status::timeout);  // draining
  chunk.clear_model();
  ASSERT_TRUE(stream->Write(chunk));  // the open stream still works
  ASSERT_TRUE(stream->Read(&d));
  EXPECT_EQ(d.points(), 20u);
  stream->WritesDone();
  while (stream->Read(&d)) {}
  EXPECT_TRUE(stream->Finish().ok());
  EXPECT_EQ(stopped.wait_for(std::chrono::seconds(10)), std::future_status::ready);
  server.running.server.reset();
}

}  // namespace
}  // namespace glimpse::server

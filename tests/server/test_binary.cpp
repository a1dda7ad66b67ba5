// The glimpse-server executable: flags, startup errors, serving with health and metrics, and a clean
// stop on SIGTERM (in-flight calls drained, store closed: no WAL left behind).
#include <arpa/inet.h>
#include <fcntl.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <grpcpp/grpcpp.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "common/free_port.h"
#include "common/temp_dir.h"
#include "glimpse/v1/glimpse.grpc.pb.h"

extern char** environ;

namespace glimpse::server {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using glimpse::testing::FreePort;
using glimpse::testing::TempDir;

// GET http://127.0.0.1:port/metrics, the body ("" when the port does not answer).
std::string Metrics(int port) {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = htons(static_cast<uint16_t>(port));
  std::string out;
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) {
    const std::string req = "GET /metrics HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n";
    if (::write(fd, req.data(), req.size()) == static_cast<ssize_t>(req.size())) {
      char buf[4096];
      for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) out.append(buf, static_cast<size_t>(n));
    }
  }
  ::close(fd);
  return out;
}

// The server as a child process, its stdout+stderr in a file.
class Process {
 public:
  Process(std::vector<std::string> args, const fs::path& output, const fs::path& cwd) : output_(output) {
    std::vector<char*> argv;
    args.insert(args.begin(), GLIMPSE_SERVER_EXE);
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    posix_spawn_file_actions_addchdir_np(&actions, cwd.c_str());
    EXPECT_EQ(posix_spawn(&pid_, GLIMPSE_SERVER_EXE, &actions, nullptr, argv.data(), environ), 0);
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Process() {
    if (pid_ > 0 && !exited_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  // The exit code, or -1 when it is still running after `timeout`.
  int Wait(std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return -1;
  }
  void Signal(int sig) { ::kill(pid_, sig); }
  std::string Output() const {
    std::ifstream in(output_);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }

 private:
  fs::path output_;
  pid_t pid_ = -1;
  bool exited_ = false;
};

TEST(Binary, HelpAndBadFlags) {
  TempDir dir;
  Process help({"--help"}, dir / "help.txt", dir / "");
  EXPECT_EQ(help.Wait(), 0);
  EXPECT_THAT(help.Output(), HasSubstr("--max-streams"));
  // Besides a word for a number: values that would overflow into another setting (a negative thread
  // count, a stream limit in the past) and a thread quota the pollers use up are refused, not served as
  // RESOURCE_EXHAUSTED on every call.
  const std::vector<std::pair<std::vector<std::string>, std::string>> refused = {
      {{"--max-points=lots"}, "--max-points"},
      {{"--max-streams=2147483648"}, "--max-streams"},
      {{"--max-stream-seconds=9223372037"}, "--max-stream-seconds"},
      {{"--threads=1", "--db=" + (dir / "t.db").string(), "--metrics-port=0"}, "--threads 1 leaves no thread to serve calls"}};
  for (size_t i = 0; i < refused.size(); ++i) {
    Process bad(refused[i].first, dir / ("bad" + std::to_string(i) + ".txt"), dir / "");
    EXPECT_EQ(bad.Wait(), 2) << refused[i].second;
    EXPECT_THAT(bad.Output(), HasSubstr(refused[i].second));
  }
}

TEST(Binary, CorruptDatabaseIsAClearStartupError) {
  TempDir dir;
  std::ofstream(dir / "bad.db") << std::string(8192, 'z');
  Process p({"--db=" + (dir / "bad.db").string(), "--metrics-port=0", "--address=127.0.0.1:" + std::to_string(FreePort())},
            dir / "out.txt", dir / "");
  EXPECT_EQ(p.Wait(), 1);
  EXPECT_THAT(p.Output(), HasSubstr("cannot open the model store"));
  EXPECT_THAT(p.Output(), HasSubstr("bad.db"));
}

TEST(Binary, AnAddressInUseIsAClearStartupError) {
  TempDir dir;
  const std::string address = "127.0.0.1:" + std::to_string(FreePort());
  Process first({"--address=" + address, "--metrics-port=0", "--db=" + (dir / "first.db").string()}, dir / "first.txt",
                dir / "");
  auto channel = grpc::CreateChannel(address, grpc::InsecureChannelCredentials());
  ASSERT_TRUE(channel->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(20))) << first.Output();
  // gRPC's default SO_REUSEPORT would let a second server share the port and take half of the calls.
  Process second({"--address=" + address, "--metrics-port=0", "--db=" + (dir / "second.db").string()},
                 dir / "second.txt", dir / "");
  EXPECT_EQ(second.Wait(), 1) << second.Output();
  EXPECT_THAT(second.Output(), HasSubstr("cannot listen on " + address));
  auto stub = v1::Glimpse::NewStub(channel);
  for (int i = 0; i < 4; ++i) {  // the first server answers every call, its store intact
    grpc::ClientContext ctx;
    v1::ListModelsResponse resp;
    EXPECT_TRUE(stub->ListModels(&ctx, v1::ListModelsRequest(), &resp).ok());
  }
  EXPECT_EQ(first.Wait(std::chrono::milliseconds(0)), -1) << "the first server is still running";
}

TEST(Binary, ServesUntilSigtermThenClosesTheStore) {
  TempDir dir;
  const int port = FreePort(), metrics_port = FreePort();
  Process p({"--address=127.0.0.1:" + std::to_string(port), "--metrics-port=" + std::to_string(metrics_port),
             "--shutdown-grace-seconds=5"},
            dir / "out.txt", dir / "");
  auto channel = grpc::CreateChannel("127.0.0.1:" + std::to_string(port), grpc::InsecureChannelCredentials());
  ASSERT_TRUE(channel->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(20))) << p.Output();
  auto stub = v1::Glimpse::NewStub(channel);
  {
    grpc::ClientContext ctx;
    v1::ListModelsResponse resp;
    ASSERT_TRUE(stub->ListModels(&ctx, v1::ListModelsRequest(), &resp).ok());
    EXPECT_EQ(resp.models_size(), 0);
  }
  {
    grpc::ClientContext ctx;
    v1::ClassifyRequest req;
    req.mutable_model()->set_name("missing");
    v1::ClassifyResponse resp;
    EXPECT_EQ(stub->Classify(&ctx, req, &resp).error_code(), grpc::StatusCode::NOT_FOUND);
  }
  EXPECT_TRUE(fs::exists(dir / "var/glimpse.db"));  // the default path, folder created

  // An open scan session when SIGTERM arrives may finish its work.
  grpc::ClientContext sctx;
  auto stream = stub->StreamClassify(&sctx);
  // Only once the server holds the stream (its handler counts it), so that the stream is in flight
  // rather than refused because it arrived after shutdown began.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (Metrics(metrics_port).find("glimpse_active_streams{method=\"StreamClassify\"} 1") == std::string::npos &&
         std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_NE(Metrics(metrics_port).find("glimpse_active_streams{method=\"StreamClassify\"} 1"), std::string::npos)
      << Metrics(metrics_port);
  p.Signal(SIGTERM);
  // Once the server has taken the signal (it says so), the stream's chunk arrives during the drain.
  const auto signalled_by = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (p.Output().find("received SIGTERM") == std::string::npos && std::chrono::steady_clock::now() < signalled_by)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_NE(p.Output().find("received SIGTERM"), std::string::npos) << p.Output();
  v1::ScanChunk chunk;
  chunk.mutable_model()->set_name("missing");
  stream->Write(chunk);
  v1::Decision d;
  stream->Read(&d);
  EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::NOT_FOUND);  // answered, not dropped

  EXPECT_EQ(p.Wait(), 0) << p.Output();
  const std::string out = p.Output();
  EXPECT_THAT(out, HasSubstr("received SIGTERM"));
  EXPECT_THAT(out, HasSubstr("rpc=ListModels"));
  EXPECT_THAT(out, HasSubstr("rpc=Classify"));
  EXPECT_THAT(out, HasSubstr("code=NOT_FOUND"));
  EXPECT_FALSE(fs::exists(dir / "var/glimpse.db-wal"));  // closed cleanly: checkpointed and removed
}

}  // namespace
}  // namespace glimpse::server

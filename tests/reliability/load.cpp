// glimpse-load: a bounded load test of the glimpse-server executable on loopback.
// Starts the server as a child process, trains a zoo model, then for --seconds runs at once:
//   --streams StreamClassify sessions (each a zoo view in --chunks chunks, again and again),
//   --classifiers threads flooding Classify with zoo views,
//   one Train of a new version of the model;
// samples the server's RSS from /proc every 250 ms, and finally checks the limits: --max-streams
// sessions held open plus a few more (RESOURCE_EXHAUSTED expected), and a cloud over --max-points.
// Prints latency percentiles, throughput, errors by code and RSS (start, peak, end); exits 1 on any
// error that is not a limit (RESOURCE_EXHAUSTED where a limit was exceeded), or if the server died.
//   glimpse-load [--server=BIN] [--seconds=30] [--streams=8] [--classifiers=2] [--chunks=10]
//                [--max-streams=16] [--max-requests=1000000] [--report=FILE.md]
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <thread>

#include "common/free_port.h"
#include "real_server.h"

extern char** environ;

namespace glimpse::reliability {
namespace {

using Clock = std::chrono::steady_clock;

struct Options {
  std::string server = GLIMPSE_SERVER_EXE;
  double seconds = 30;
  int streams = 8;
  int classifiers = 2;
  int chunks = 10;
  int max_streams = 16;
  long max_requests = 1'000'000;  // a hard cap on the calls of the main phase, whatever the time
  std::string report;
};

bool Parse(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto eq = a.find('=');
    if (a.rfind("--", 0) != 0 || eq == std::string::npos) return false;
    const std::string k = a.substr(2, eq - 2), v = a.substr(eq + 1);
    try {
      if (k == "server") o.server = v;
      else if (k == "seconds") o.seconds = std::stod(v);
      else if (k == "streams") o.streams = std::stoi(v);
      else if (k == "classifiers") o.classifiers = std::stoi(v);
      else if (k == "chunks") o.chunks = std::stoi(v);
      else if (k == "max-streams") o.max_streams = std::stoi(v);
      else if (k == "max-requests") o.max_requests = std::stol(v);
      else if (k == "report") o.report = v;
      else return false;
    } catch (...) {
      return false;
    }
  }
  return o.seconds > 0 && o.seconds <= 3600 && o.streams >= 0 && o.classifiers >= 0 && o.chunks >= 1 &&
         o.max_streams >= 1 && o.streams + 1 <= o.max_streams;
}

long RssKiB(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

// Latencies and outcomes of one kind of call.
struct Series {
  std::mutex m;
  std::vector<double> ms;
  std::map<std::string, long> codes;
  void Add(double latency_ms, grpc::StatusCode code) {
    std::lock_guard lock(m);
    if (code == grpc::StatusCode::OK) ms.push_back(latency_ms);
    ++codes[wire::StatusCodeName(code)];
  }
  double Percentile(double p) {
    std::lock_guard lock(m);
    if (ms.empty()) return 0;
    std::vector<double> s = ms;
    const size_t k = std::min(s.size() - 1, static_cast<size_t>(p / 100.0 * double(s.size())));
    std::nth_element(s.begin(), s.begin() + long(k), s.end());
    return s[k];
  }
  long Count(const std::string& code) {
    std::lock_guard lock(m);
    return codes.count(code) ? codes[code] : 0;
  }
  long Errors(bool limits) {  // limits: RESOURCE_EXHAUSTED only; else every other non-OK code
    std::lock_guard lock(m);
    long n = 0;
    for (const auto& [c, k] : codes)
      if (c != "OK" && (c == "RESOURCE_EXHAUSTED") == limits) n += k;
    return n;
  }
  std::string Codes() {
    std::lock_guard lock(m);
    std::string s;
    for (const auto& [c, k] : codes) s += (s.empty() ? "" : ", ") + c + " " + std::to_string(k);
    return s.empty() ? "-" : s;
  }
};

std::vector<v1::ScanChunk> Chunks(const Cloud& view, int n) {
  std::vector<v1::ScanChunk> out;
  const size_t per = (view.points.size() + size_t(n) - 1) / size_t(n);
  for (int k = 0; k < n; ++k) {
    Cloud part;
    for (size_t i = size_t(k) * per; i < std::min(view.points.size(), size_t(k + 1) * per); ++i)
      part.points.push_back(view.points[i]);
    v1::ScanChunk c;
    if (k == 0) c.mutable_model()->set_name("zoo");
    *c.mutable_cloud() = wire::CloudToProto(part);
    out.push_back(std::move(c));
  }
  return out;
}

// glimpse-server as a child process on 127.0.0.1:port, its output in `log`; its pid, or -1.
pid_t StartServer(const Options& o, int port, const TempDir& dir, const std::string& log) {
  std::vector<std::string> args = {o.server, "--address=127.0.0.1:" + std::to_string(port),
                                   "--db=" + dir.file("models.db"), "--metrics-port=0",
                                   "--max-streams=" + std::to_string(o.max_streams), "--max-points=200000"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = -1;
  const bool started = posix_spawn(&pid, o.server.c_str(), &actions, nullptr, argv.data(), environ) == 0;
  posix_spawn_file_actions_destroy(&actions);
  return started ? pid : -1;
}

v1::ClassifyRequest ZooRequest(const Cloud& cloud) {
  v1::ClassifyRequest req;
  req.mutable_model()->set_name("zoo");
  *req.mutable_cloud() = wire::CloudToProto(cloud);
  return req;
}

// Unseen shapes for Classify and streams; views core rejects (too few keypoints for BoK, ...) are
// left out, so that every error of the load is the server's, not the input's.
std::vector<TrainingCloud> ProbeViews(v1::Glimpse::Stub& stub, size_t& rejected) {
  std::vector<TrainingCloud> probe_views;
  for (TrainingCloud& v : ZooViews(2, 1000, 3)) {
    grpc::ClientContext ctx;
    v1::ClassifyResponse resp;
    if (stub.Classify(&ctx, ZooRequest(v.cloud), &resp).ok()) probe_views.push_back(std::move(v));
    else ++rejected;
  }
  return probe_views;
}

// The server's RSS from /proc every 250 ms, as (seconds since the start, KiB), until Stop.
class RssSampler {
 public:
  explicit RssSampler(pid_t pid)
      : start_(Clock::now()), thread_([this, pid] {
          while (!stop_) {
            samples_.emplace_back(Seconds(), RssKiB(pid));
            std::this_thread::sleep_for(std::chrono::milliseconds(250));
          }
        }) {}
  ~RssSampler() { Stop(); }
  double Seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
  std::vector<std::pair<double, long>> Stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    return samples_;
  }

 private:
  Clock::time_point start_;
  std::atomic<bool> stop_{false};
  std::vector<std::pair<double, long>> samples_;
  std::thread thread_;  // declared last: it starts once the rest is built
};

// What the load measures, by kind of call, and how the server came out of it.
struct Outcome {
  Series classify, chunk, stream_calls, train;  // the main phase
  Series limit_streams, limit_points;           // the limits
  double main_seconds = 0;
  bool alive = false, serving = false;

  long NonLimitErrors() {
    return classify.Errors(false) + stream_calls.Errors(false) + train.Errors(false) + classify.Errors(true) +
           stream_calls.Errors(true) + train.Errors(true) + (4 - limit_streams.Count("RESOURCE_EXHAUSTED")) +
           (1 - limit_points.Count("RESOURCE_EXHAUSTED"));
  }
};

using Running = std::function<bool()>;

void FloodClassify(v1::Glimpse::Stub& stub, const std::vector<TrainingCloud>& views, size_t first, size_t step,
                   const Running& running, std::atomic<long>& calls, Series& out) {
  for (size_t i = first; running(); i += step) {
    grpc::ClientContext ctx;
    ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    v1::ClassifyResponse resp;
    const auto t0 = Clock::now();
    grpc::Status s = stub.Classify(&ctx, ZooRequest(views[i % views.size()].cloud), &resp);
    out.Add(std::chrono::duration<double, std::milli>(Clock::now() - t0).count(), s.error_code());
    ++calls;
  }
}

void RepeatStreams(v1::Glimpse::Stub& stub, const std::vector<TrainingCloud>& views, size_t first, size_t step,
                   int chunk_count, const Running& running, std::atomic<long>& calls, Outcome& out) {
  for (size_t i = first; running(); i += step) {
    const auto chunks = Chunks(views[i % views.size()].cloud, chunk_count);
    grpc::ClientContext ctx;
    ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
    auto stream = stub.StreamClassify(&ctx);
    const auto s0 = Clock::now();
    for (const auto& c : chunks) {
      const auto t0 = Clock::now();
      v1::Decision d;
      if (!stream->Write(c) || !stream->Read(&d)) break;
      out.chunk.Add(std::chrono::duration<double, std::milli>(Clock::now() - t0).count(), grpc::StatusCode::OK);
      ++calls;
    }
    stream->WritesDone();
    for (v1::Decision final; stream->Read(&final);) {}  // the final decision (the whole scan)
    grpc::Status s = stream->Finish();
    out.stream_calls.Add(std::chrono::duration<double, std::milli>(Clock::now() - s0).count(), s.error_code());
  }
}

// Streams + Classify flood + one Train, all at once, for --seconds or --max-requests calls.
void MainPhase(const Options& o, v1::Glimpse::Stub& stub, const std::vector<TrainingCloud>& probe_views,
               const std::vector<TrainingCloud>& train_data, Outcome& out) {
  std::atomic<long> calls{0};
  const auto end = Clock::now() + std::chrono::milliseconds(long(o.seconds * 1000));
  const Running running = [&] { return Clock::now() < end && calls.load() < o.max_requests; };
  std::vector<std::thread> workers;
  for (int c = 0; c < o.classifiers; ++c)
    workers.emplace_back([&, c] {
      FloodClassify(stub, probe_views, size_t(c), size_t(o.classifiers), running, calls, out.classify);
    });
  for (int k = 0; k < o.streams; ++k)
    workers.emplace_back([&, k] {
      RepeatStreams(stub, probe_views, size_t(k), size_t(o.streams), o.chunks, running, calls, out);
    });
  workers.emplace_back([&] {
    const auto t0 = Clock::now();
    grpc::Status s = TrainStream(stub, TrainMessages(FastTrainHeader("zoo"), train_data), nullptr, std::chrono::minutes(10));
    out.train.Add(std::chrono::duration<double, std::milli>(Clock::now() - t0).count(), s.error_code());
  });
  for (auto& w : workers) w.join();
}

// Every stream slot held, then 4 more (RESOURCE_EXHAUSTED expected).
void HoldEveryStream(const Options& o, v1::Glimpse::Stub& stub, Series& out) {
  std::vector<std::unique_ptr<grpc::ClientContext>> ctxs;
  std::vector<std::unique_ptr<grpc::ClientReaderWriter<v1::ScanChunk, v1::Decision>>> held;
  int opened = 0;
  v1::ScanChunk first;
  first.mutable_model()->set_name("zoo");
  for (int i = 0; i < o.max_streams; ++i) {
    ctxs.push_back(std::make_unique<grpc::ClientContext>());
    held.push_back(stub.StreamClassify(ctxs.back().get()));
    v1::Decision d;
    if (held.back()->Write(first) && held.back()->Read(&d)) ++opened;
  }
  for (int i = 0; i < 4; ++i) {
    grpc::ClientContext ctx;
    auto extra = stub.StreamClassify(&ctx);
    extra->Write(first);
    v1::Decision d;
    extra->Read(&d);
    extra->WritesDone();
    while (extra->Read(&d)) {}
    out.Add(0, extra->Finish().error_code());
  }
  for (auto& h : held) {
    h->WritesDone();
    for (v1::Decision rest; h->Read(&rest);) {}
    h->Finish();
  }
  if (opened != o.max_streams) std::fprintf(stderr, "glimpse-load: only %d of %d slots opened\n", opened, o.max_streams);
}

// A cloud over --max-points (RESOURCE_EXHAUSTED expected).
void SendHugeCloud(v1::Glimpse::Stub& stub, Series& out) {
  Cloud huge;
  huge.points.assign(200'001, Vec3(0.1f, 0.2f, 0.3f));
  grpc::ClientContext ctx;
  v1::ClassifyResponse resp;
  out.Add(0, stub.Classify(&ctx, ZooRequest(huge), &resp).error_code());
}

// The markdown report: calls, RSS, limits, errors.
std::string Report(const Options& o, size_t probe_views, size_t rejected,
                   const std::vector<std::pair<double, long>>& rss, Outcome& out) {
  long rss_start = -1, rss_peak = 0, rss_end = -1;
  for (const auto& [t, kib] : rss) {
    if (rss_start < 0 && t >= 1.0) rss_start = kib;  // after the first second: connections set up
    rss_peak = std::max(rss_peak, kib);
    if (t <= out.main_seconds) rss_end = kib;
  }
  const long limit_ok = out.limit_streams.Count("RESOURCE_EXHAUSTED") + out.limit_points.Count("RESOURCE_EXHAUSTED");
  std::ostringstream r;
  char line[512];
  r << "## glimpse-load: " << o.streams << " StreamClassify sessions + " << o.classifiers
    << " Classify threads + 1 Train, " << o.seconds << " s on loopback\n\n";
  r << probe_views << " zoo views of unseen shapes (" << rejected << " left out: core rejects them).\n\n";
  r << "| calls | count | per s | p50 ms | p99 ms | outcomes |\n|---|---|---|---|---|---|\n";
  auto row = [&](const char* name, Series& s, long count) {
    std::snprintf(line, sizeof line, "| %s | %ld | %.1f | %.1f | %.1f | %s |\n", name, count,
                  double(count) / out.main_seconds, s.Percentile(50), s.Percentile(99), s.Codes().c_str());
    r << line;
  };
  auto total = [](const Series& s) {
    long n = 0;
    for (auto& [c, k] : s.codes) n += k;
    return n;
  };
  row("Classify", out.classify, total(out.classify));
  row("StreamClassify chunk (round trip)", out.chunk, total(out.chunk));
  row("StreamClassify session", out.stream_calls, total(out.stream_calls));
  row("Train (concurrent)", out.train, 1);
  std::snprintf(line, sizeof line,
                "\nServer RSS: %.1f MiB at 1 s, peak %.1f MiB, %.1f MiB at the end of the load (%+.1f %%), %zu samples.\n",
                rss_start / 1024.0, rss_peak / 1024.0, rss_end / 1024.0,
                rss_start > 0 ? 100.0 * double(rss_end - rss_start) / double(rss_start) : 0.0, rss.size());
  r << line;
  r << "Limits: " << o.max_streams << " sessions held + 4 more -> " << out.limit_streams.Codes()
    << "; a cloud of 200001 points (--max-points 200000) -> " << out.limit_points.Codes() << ".\n";
  r << "Non-limit errors: " << out.NonLimitErrors() << "; limit answers as expected: " << limit_ok << " of 5; server "
    << (out.alive && out.serving ? "alive and serving" : "NOT serving") << " afterwards.\n";
  return r.str();
}

void PrintLogTail(const std::string& log) {
  std::ifstream in(log);
  std::stringstream s;
  s << in.rdbuf();
  std::fprintf(stderr, "---- server log ----\n%s\n", s.str().substr(s.str().size() > 4000 ? s.str().size() - 4000 : 0).c_str());
}

int Run(const Options& o) {
  const int port = glimpse::testing::FreePort();
  const TempDir dir("load");  // outlives the reaper below: the server stops before its folder goes
  const std::string log = dir.file("server.log");
  const pid_t pid = StartServer(o, port, dir, log);
  if (pid < 0) {
    std::fprintf(stderr, "glimpse-load: cannot start %s\n", o.server.c_str());
    return 2;
  }
  struct Reaper {
    pid_t pid;
    ~Reaper() {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  } reaper{pid};
  grpc::ChannelArguments cargs;
  cargs.SetMaxSendMessageSize(64 << 20);
  auto channel = grpc::CreateCustomChannel("127.0.0.1:" + std::to_string(port), grpc::InsecureChannelCredentials(), cargs);
  if (!channel->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(20))) {
    std::fprintf(stderr, "glimpse-load: the server did not start (see its log)\n");
    return 2;
  }
  auto stub = v1::Glimpse::NewStub(channel);
  const auto train_data = ZooViews(2, 7, 2);
  if (grpc::Status trained = TrainStream(*stub, TrainMessages(FastTrainHeader("zoo"), train_data)); !trained.ok()) {
    std::fprintf(stderr, "glimpse-load: the first Train failed: %s\n", trained.error_message().c_str());
    return 1;
  }
  size_t rejected = 0;
  const std::vector<TrainingCloud> probe_views = ProbeViews(*stub, rejected);
  if (probe_views.empty()) {
    std::fprintf(stderr, "glimpse-load: no probe view classifies\n");
    return 1;
  }

  RssSampler sampler(pid);
  Outcome out;
  MainPhase(o, *stub, probe_views, train_data, out);
  out.main_seconds = sampler.Seconds();
  HoldEveryStream(o, *stub, out.limit_streams);
  SendHugeCloud(*stub, out.limit_points);
  // Still serving after the limits?
  grpc::ClientContext after_ctx;
  v1::ClassifyResponse after_resp;
  out.serving = stub->Classify(&after_ctx, ZooRequest(probe_views[0].cloud), &after_resp).ok() && HealthStatus(channel) == 1;
  const auto rss = sampler.Stop();
  int status = 0;
  out.alive = ::waitpid(pid, &status, WNOHANG) == 0;

  const std::string report = Report(o, probe_views.size(), rejected, rss, out);
  std::fputs(report.c_str(), stdout);
  if (!o.report.empty()) std::ofstream(o.report) << report;
  if (!out.alive || !out.serving) PrintLogTail(log);
  return out.NonLimitErrors() == 0 && out.alive && out.serving ? 0 : 1;
}

}  // namespace
}  // namespace glimpse::reliability

int main(int argc, char** argv) {
  glimpse::reliability::Options o;
  if (!glimpse::reliability::Parse(argc, argv, o)) {
    std::fprintf(stderr,
                 "usage: glimpse-load [--server=BIN] [--seconds=30] [--streams=8] [--classifiers=2] [--chunks=10]\n"
                 "                    [--max-streams=16] [--max-requests=1000000] [--report=FILE.md]\n"
                 "(--streams + 1 must not exceed --max-streams)\n");
    return 2;
  }
  return glimpse::reliability::Run(o);
}

// glimpse-load: a bounded load test of the glimpse-server executable on loopback (issue 10, item 5).
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
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

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

int FreePort() {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
  socklen_t len = sizeof addr;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  ::close(fd);
  return ntohs(addr.sin_port);
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
    ++codes[server::StatusCodeName(code)];
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
    *c.mutable_cloud() = server::CloudToProto(part);
    out.push_back(std::move(c));
  }
  return out;
}

int Run(const Options& o) {
  // ---- the server, as a child process ----
  const int port = FreePort();
  char tmpl[] = "/tmp/glimpse-load.XXXXXX";
  if (!::mkdtemp(tmpl)) return 2;
  const std::string dir = tmpl, log = dir + "/server.log";
  std::vector<std::string> args = {o.server, "--address=127.0.0.1:" + std::to_string(port), "--db=" + dir + "/models.db",
                                   "--metrics-port=0", "--max-streams=" + std::to_string(o.max_streams),
                                   "--max-points=200000"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = -1;
  if (posix_spawn(&pid, o.server.c_str(), &actions, nullptr, argv.data(), environ) != 0) {
    std::fprintf(stderr, "glimpse-load: cannot start %s\n", o.server.c_str());
    return 2;
  }
  posix_spawn_file_actions_destroy(&actions);
  struct Reaper {
    pid_t pid;
    std::string dir;
    ~Reaper() {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
      std::filesystem::remove_all(dir);
    }
  } reaper{pid, dir};

  grpc::ChannelArguments cargs;
  cargs.SetMaxSendMessageSize(64 << 20);
  auto channel = grpc::CreateCustomChannel("127.0.0.1:" + std::to_string(port), grpc::InsecureChannelCredentials(), cargs);
  if (!channel->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(20))) {
    std::fprintf(stderr, "glimpse-load: the server did not start (see its log)\n");
    return 2;
  }
  auto stub = v1::Glimpse::NewStub(channel);

  const auto train_data = ZooViews(2, 7, 2);
  grpc::Status trained = TrainStream(*stub, TrainMessages(SmallHeader("zoo"), train_data));
  if (!trained.ok()) {
    std::fprintf(stderr, "glimpse-load: the first Train failed: %s\n", trained.error_message().c_str());
    return 1;
  }
  // Unseen shapes for Classify and streams; views core rejects (too few keypoints for BoK, ...) are
  // left out, so that every error of the load is the server's, not the input's.
  std::vector<TrainingCloud> probe_views;
  size_t rejected = 0;
  for (TrainingCloud& v : ZooViews(2, 1000, 3)) {
    v1::ClassifyRequest req;
    req.mutable_model()->set_name("zoo");
    *req.mutable_cloud() = server::CloudToProto(v.cloud);
    grpc::ClientContext ctx;
    v1::ClassifyResponse resp;
    if (stub->Classify(&ctx, req, &resp).ok()) probe_views.push_back(std::move(v));
    else ++rejected;
  }
  if (probe_views.empty()) {
    std::fprintf(stderr, "glimpse-load: no probe view classifies\n");
    return 1;
  }

  // ---- RSS sampler ----
  std::atomic<bool> stop_sampling{false};
  std::vector<std::pair<double, long>> rss;  // (seconds, KiB)
  const auto t_start = Clock::now();
  auto since = [&] { return std::chrono::duration<double>(Clock::now() - t_start).count(); };
  std::thread sampler([&] {
    while (!stop_sampling) {
      rss.emplace_back(since(), RssKiB(pid));
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
  });

  // ---- main phase: streams + Classify flood + one Train, all at once ----
  Series classify, chunk, stream_calls, train;
  std::atomic<long> calls{0};
  const auto end = Clock::now() + std::chrono::milliseconds(long(o.seconds * 1000));
  auto running = [&] { return Clock::now() < end && calls.load() < o.max_requests; };
  std::vector<std::thread> workers;
  for (int c = 0; c < o.classifiers; ++c)
    workers.emplace_back([&, c] {
      for (size_t i = size_t(c); running(); i += size_t(o.classifiers)) {
        v1::ClassifyRequest req;
        req.mutable_model()->set_name("zoo");
        *req.mutable_cloud() = server::CloudToProto(probe_views[i % probe_views.size()].cloud);
        grpc::ClientContext ctx;
        ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
        v1::ClassifyResponse resp;
        const auto t0 = Clock::now();
        grpc::Status s = stub->Classify(&ctx, req, &resp);
        classify.Add(std::chrono::duration<double, std::milli>(Clock::now() - t0).count(), s.error_code());
        ++calls;
      }
    });
  for (int k = 0; k < o.streams; ++k)
    workers.emplace_back([&, k] {
      for (size_t i = size_t(k); running(); i += size_t(o.streams)) {
        const auto chunks = Chunks(probe_views[i % probe_views.size()].cloud, o.chunks);
        grpc::ClientContext ctx;
        ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
        auto stream = stub->StreamClassify(&ctx);
        const auto s0 = Clock::now();
        for (const auto& c : chunks) {
          const auto t0 = Clock::now();
          v1::Decision d;
          if (!stream->Write(c) || !stream->Read(&d)) break;
          chunk.Add(std::chrono::duration<double, std::milli>(Clock::now() - t0).count(), grpc::StatusCode::OK);
          ++calls;
        }
        stream->WritesDone();
        for (v1::Decision final; stream->Read(&final);) {}  // the final decision (the whole scan)
        grpc::Status s = stream->Finish();
        stream_calls.Add(std::chrono::duration<double, std::milli>(Clock::now() - s0).count(), s.error_code());
      }
    });
  workers.emplace_back([&] {
    const auto t0 = Clock::now();
    grpc::Status s = TrainStream(*stub, TrainMessages(SmallHeader("zoo"), train_data), nullptr, std::chrono::minutes(10));
    train.Add(std::chrono::duration<double, std::milli>(Clock::now() - t0).count(), s.error_code());
  });
  for (auto& w : workers) w.join();
  const double main_seconds = since();

  // ---- limits: every stream slot held, then more; a cloud over --max-points ----
  Series limit_streams, limit_points;
  {
    std::vector<std::unique_ptr<grpc::ClientContext>> ctxs;
    std::vector<std::unique_ptr<grpc::ClientReaderWriter<v1::ScanChunk, v1::Decision>>> held;
    int opened = 0;
    for (int i = 0; i < o.max_streams; ++i) {
      ctxs.push_back(std::make_unique<grpc::ClientContext>());
      held.push_back(stub->StreamClassify(ctxs.back().get()));
      v1::ScanChunk first;
      first.mutable_model()->set_name("zoo");
      v1::Decision d;
      if (held.back()->Write(first) && held.back()->Read(&d)) ++opened;
    }
    for (int i = 0; i < 4; ++i) {
      grpc::ClientContext ctx;
      auto extra = stub->StreamClassify(&ctx);
      v1::ScanChunk first;
      first.mutable_model()->set_name("zoo");
      extra->Write(first);
      v1::Decision d;
      extra->Read(&d);
      extra->WritesDone();
      while (extra->Read(&d)) {}
      limit_streams.Add(0, extra->Finish().error_code());
    }
    for (auto& h : held) {
      h->WritesDone();
      for (v1::Decision rest; h->Read(&rest);) {}
      h->Finish();
    }
    if (opened != o.max_streams) std::fprintf(stderr, "glimpse-load: only %d of %d slots opened\n", opened, o.max_streams);
    Cloud huge;
    huge.points.assign(200'001, Vec3(0.1f, 0.2f, 0.3f));
    v1::ClassifyRequest req;
    req.mutable_model()->set_name("zoo");
    *req.mutable_cloud() = server::CloudToProto(huge);
    grpc::ClientContext ctx;
    v1::ClassifyResponse resp;
    limit_points.Add(0, stub->Classify(&ctx, req, &resp).error_code());
  }
  // Still serving after the limits?
  v1::ClassifyRequest after;
  after.mutable_model()->set_name("zoo");
  *after.mutable_cloud() = server::CloudToProto(probe_views[0].cloud);
  grpc::ClientContext after_ctx;
  v1::ClassifyResponse after_resp;
  const bool serving = stub->Classify(&after_ctx, after, &after_resp).ok() && HealthStatus(channel) == 1;
  stop_sampling = true;
  sampler.join();
  int status = 0;
  const bool alive = ::waitpid(pid, &status, WNOHANG) == 0;

  // ---- report ----
  long rss_start = -1, rss_peak = 0, rss_end = -1;
  for (const auto& [t, kib] : rss) {
    if (rss_start < 0 && t >= 1.0) rss_start = kib;  // after the first second: connections set up
    rss_peak = std::max(rss_peak, kib);
    if (t <= main_seconds) rss_end = kib;
  }
  const long limit_ok = limit_streams.Count("RESOURCE_EXHAUSTED") + limit_points.Count("RESOURCE_EXHAUSTED");
  const long non_limit = classify.Errors(false) + stream_calls.Errors(false) + train.Errors(false) +
                         classify.Errors(true) + stream_calls.Errors(true) + train.Errors(true) +
                         (4 - limit_streams.Count("RESOURCE_EXHAUSTED")) + (1 - limit_points.Count("RESOURCE_EXHAUSTED"));
  std::ostringstream r;
  char line[512];
  r << "## glimpse-load: " << o.streams << " StreamClassify sessions + " << o.classifiers
    << " Classify threads + 1 Train, " << o.seconds << " s on loopback\n\n";
  r << probe_views.size() << " zoo views of unseen shapes (" << rejected << " left out: core rejects them).\n\n";
  r << "| calls | count | per s | p50 ms | p99 ms | outcomes |\n|---|---|---|---|---|---|\n";
  auto row = [&](const char* name, Series& s, long count) {
    std::snprintf(line, sizeof line, "| %s | %ld | %.1f | %.1f | %.1f | %s |\n", name, count, double(count) / main_seconds,
                  s.Percentile(50), s.Percentile(99), s.Codes().c_str());
    r << line;
  };
  long nclassify = 0, nchunks = 0, nstreams = 0;
  for (auto& [c, k] : classify.codes) nclassify += k;
  for (auto& [c, k] : chunk.codes) nchunks += k;
  for (auto& [c, k] : stream_calls.codes) nstreams += k;
  row("Classify", classify, nclassify);
  row("StreamClassify chunk (round trip)", chunk, nchunks);
  row("StreamClassify session", stream_calls, nstreams);
  row("Train (concurrent)", train, 1);
  std::snprintf(line, sizeof line,
                "\nServer RSS: %.1f MiB at 1 s, peak %.1f MiB, %.1f MiB at the end of the load (%+.1f %%), %zu samples.\n",
                rss_start / 1024.0, rss_peak / 1024.0, rss_end / 1024.0,
                rss_start > 0 ? 100.0 * double(rss_end - rss_start) / double(rss_start) : 0.0, rss.size());
  r << line;
  r << "Limits: " << o.max_streams << " sessions held + 4 more -> " << limit_streams.Codes() << "; a cloud of 200001 points"
    << " (--max-points 200000) -> " << limit_points.Codes() << ".\n";
  r << "Non-limit errors: " << non_limit << "; limit answers as expected: " << limit_ok << " of 5; server "
    << (alive && serving ? "alive and serving" : "NOT serving") << " afterwards.\n";
  std::fputs(r.str().c_str(), stdout);
  if (!o.report.empty()) std::ofstream(o.report) << r.str();
  if (!alive || !serving) {
    std::ifstream in(log);
    std::stringstream s;
    s << in.rdbuf();
    std::fprintf(stderr, "---- server log ----\n%s\n", s.str().substr(s.str().size() > 4000 ? s.str().size() - 4000 : 0).c_str());
  }
  return non_limit == 0 && alive && serving ? 0 : 1;
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

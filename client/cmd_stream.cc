// glimpse stream: a simulated scanner. One single view of an object (a cloud file as it is, or a
// view of a mesh or zoo shape) is revealed chunk by chunk over StreamClassify at a fixed rate, and the
// server's evolving decision is shown live, then the final one (Classify's of the whole scan).
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <stop_token>
#include <thread>

#include "client/commands.h"
#include "client/frames.h"
#include "client/parse.h"
#include "client/render.h"
#include "client/scan.h"
#include "proto/wire/clouds.h"
#include "proto/wire/methods.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/zoo.h"

namespace glimpse::client {
namespace {

// Prints decisions: a panel redrawn in place on a terminal, else one line (or JSON object) each.
class DecisionView {
 public:
  DecisionView(size_t chunks, bool json) : chunks_(chunks), json_(json), tty_(!json && IsTerminal(stdout)) {}
  void Show(const v1::Decision& d) {
    if (json_) {
      PrintOut(DecisionJson(d, chunks_) + "\n");
    } else if (!tty_) {
      PrintOut(DecisionLine(d, chunks_) + "\n");
    } else {
      const std::string panel = DecisionPanel(d, chunks_, previous_);
      // Back to the panel's first line, clear to the end of the screen, draw again.
      PrintOut((lines_ ? "\x1b[" + std::to_string(lines_) + "A\r\x1b[J" : std::string()) + panel);
      lines_ = LineCount(panel);
    }
    if (!d.winner().empty()) previous_ = d.winner();
  }

 private:
  size_t chunks_;
  bool json_, tty_;
  int lines_ = 0;
  std::string previous_;
};

// The scanner: chunks go out at the given rate whatever the server's pace, as a sensor's would; the
// first names the model, the method and the operating point.
void SendChunks(std::stop_token stop, grpc::ClientReaderWriter<v1::ScanChunk, v1::Decision>& stream,
                const std::vector<Cloud>& scan, const StreamOptions& o) {
  std::mutex mu;
  std::condition_variable_any wake;
  const auto start = std::chrono::steady_clock::now();
  v1::ScanChunk chunk;
  if (!o.model.empty()) *chunk.mutable_model() = *ParseModelRef(o.model);
  if (!o.method.empty()) chunk.set_method(*wire::ParseMethod(o.method));
  chunk.set_known_acceptance(o.known_acceptance);
  if (o.track) *chunk.mutable_track() = *o.track;
  for (size_t i = 0; i < scan.size(); ++i) {
    if (o.rate_hz > 0 && i > 0) {
      const auto due = start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                   std::chrono::duration<double>(static_cast<double>(i) / o.rate_hz));
      std::unique_lock lock(mu);
      if (wake.wait_until(lock, stop, due, [] { return false; }), stop.stop_requested()) return;
    }
    wire::CloudToProto(scan[i], chunk.mutable_cloud());
    if (!stream.Write(chunk)) return;  // the call ended; Finish tells why
    if (i == 0) {
      chunk.clear_model();
      chunk.clear_method();
      chunk.clear_known_acceptance();
      chunk.clear_track();
    }
  }
  stream.WritesDone();
}

}  // namespace

Expected<Cloud> StreamView(const StreamOptions& o) {
  if (!o.zoo_category.empty()) {
    auto mesh = make_zoo_shape(o.zoo_category, o.seed);
    if (!mesh) return mesh.error();
    Cloud full = mesh_vertices(*mesh);
    RemoveNonFinite(full);
    return SingleView(full, o.viewpoint.value_or(0), o.protocol.hpr_radius_factor);
  }
  auto file = LoadFile(o.file);
  if (!file) return file.error();
  if (Status s = ApplyCameraFov(*file, o.camera_fov, o.file); !s.ok()) return s.error();
  if (Status s = ApplySensor(*file, o.sensor, o.file); !s.ok()) return s.error();
  if (file->is_mesh) {
    ViewRecipe protocol = o.protocol;
    protocol.seed = o.seed;
    return MeshFileView(o.file, o.placement, protocol, o.viewpoint.value_or(0));
  }
  RemoveNonFinite(file->cloud);
  if (Status s = PlaceCloud(file->cloud, o.placement, o.file); !s.ok()) return s.error();
  // A cloud file is the scan: it streams as it is (or as --unit / --up place it), with its sensor if it
  // has one (wherever that is), and is cut into a new view only when asked.
  if (!o.viewpoint) return std::move(file->cloud);
  return SingleView(file->cloud, *o.viewpoint, o.protocol.hpr_radius_factor);
}

Expected<std::vector<Cloud>> StreamChunks(const StreamOptions& o) {
  if (!o.frames_dir.empty()) {
    auto frames = LoadFrames(o.frames_dir);
    if (!frames.ok()) return frames.error();
    std::vector<Cloud> chunks = FrameChunks(*frames, o.chunk_points);
    for (Cloud& chunk : chunks)  // the common frame's unit and up, sensors with their points
      if (Status s = PlaceCloud(chunk, o.placement, o.frames_dir); !s.ok()) return s.error();
    return chunks;
  }
  auto order = ParseRevealOrder(o.order);
  if (!order) return order.error();
  auto view = StreamView(o);
  if (!view) return view.error();
  const Cloud scan = Reordered(*view, RevealSequence(*view, *order, o.seed));
  const std::vector<size_t> ends = ChunkEnds(scan.points.size(), o.chunks, o.chunk_points);
  if (ends.empty()) return invalid_argument("the view has no points");
  std::vector<Cloud> chunks(ends.size());
  for (size_t i = 0; i < ends.size(); ++i) {
    chunks[i].sensor = scan.sensor;
    chunks[i].frame = scan.frame;
    chunks[i].points.assign(scan.points.begin() + std::ptrdiff_t(i ? ends[i - 1] : 0),
                            scan.points.begin() + std::ptrdiff_t(ends[i]));
  }
  return chunks;
}

int RunStream(const ConnectionOptions& conn, const StreamOptions& o) {
  const std::string what = "stream " + (!o.frames_dir.empty()     ? "--frames " + o.frames_dir
                                        : o.zoo_category.empty() ? o.file
                                                                 : "--zoo " + o.zoo_category);
  if (auto order = ParseRevealOrder(o.order); !order) {
    PrintError(what, order.error().message);
    return kExitUsage;
  }
  auto chunks = StreamChunks(o);
  if (!chunks) {
    PrintError(what, chunks.error().message);
    return kExitError;
  }
  const std::vector<Cloud>& scan = *chunks;
  auto stub = ConnectGlimpse(conn, what);
  if (!stub) return kExitError;

  grpc::ClientContext context;
  const double scan_s = o.rate_hz > 0 ? static_cast<double>(scan.size()) / o.rate_hz : 0.0;
  PrepareContext(context, conn, 120 + scan_s);
  auto stream = stub->StreamClassify(&context);

  std::jthread scanner([&](std::stop_token stop) { SendChunks(stop, *stream, scan, o); });
  DecisionView shown(scan.size(), o.json);
  v1::Decision decision;
  size_t answered = 0;
  std::string final_unknown;  // why the final decision is "unknown", said on stderr as classify says it
  while (stream->Read(&decision)) {
    shown.Show(decision);
    if (!decision.final()) ++answered;
    else if (decision.unknown()) final_unknown = decision.unknown_reason();
  }
  scanner.request_stop();  // wakes it from the rate wait; a pending Write fails now the call is over
  scanner.join();
  const grpc::Status status = stream->Finish();
  if (!status.ok()) {
    PrintError(what, FormatStatus(status));
    return kExitError;
  }
  if (!o.json && !final_unknown.empty()) PrintError(what, "unknown: " + final_unknown);
  if (answered < scan.size()) {
    PrintError(what, "the server answered " + std::to_string(answered) + " of " + std::to_string(scan.size()) +
                         " chunks");
    return kExitError;
  }
  return kExitOk;
}

}  // namespace glimpse::client

#include "convert.h"

#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

namespace glimpse::server {
namespace {

constexpr size_t kBytesPerPoint = 12;
constexpr size_t kMaxNameLength = 128;
constexpr size_t kMaxDescriptionBytes = 4096;
// Clouds are in metres; beyond 1000 km float32 has no centimetres left, and core's voxel keys and
// kd-tree splits overflow near float's range (a cloud at 3e38 m aborted the server in PCL's kd-tree).
constexpr float kMaxAbsCoordinateM = 1e6f;

float ReadFloatLE(const char* p) {
  uint32_t u = 0;
  for (int i = 3; i >= 0; --i) u = (u << 8) | static_cast<uint8_t>(p[i]);
  return std::bit_cast<float>(u);
}

void AppendFloatLE(std::string& out, float f) {
  uint32_t u = std::bit_cast<uint32_t>(f);
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((u >> (8 * i)) & 0xff));
}

// Decodes packed triples into `points`; `what` names the field in errors.
Status Unpack(const std::string& bytes, std::string_view what, Points& points) {
  if (bytes.size() % kBytesPerPoint != 0)
    return invalid_argument(std::string(what) + " has " + std::to_string(bytes.size()) +
                            " bytes; it must be a multiple of 12 (packed little-endian float32 x, y, z)");
  const size_t n = bytes.size() / kBytesPerPoint;
  points.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const char* p = bytes.data() + i * kBytesPerPoint;
    Vec3 v(ReadFloatLE(p), ReadFloatLE(p + 4), ReadFloatLE(p + 8));
    if (!v.allFinite())
      return invalid_argument(std::string(what) + ": point " + std::to_string(i) + " is not finite");
    if (v.cwiseAbs().maxCoeff() > kMaxAbsCoordinateM)
      return invalid_argument(std::string(what) + ": point " + std::to_string(i) +
                              " has a coordinate beyond +-1e6 m (clouds are in metres)");
    points[i] = v;
  }
  return {};
}

}  // namespace

Expected<Cloud> CloudFromProto(const v1::PointCloud& msg, size_t max_points) {
  const size_t n = msg.xyz().size() / kBytesPerPoint;
  if (n > max_points)
    return resource_exhausted("cloud has " + std::to_string(n) + " points; the limit is " + std::to_string(max_points));
  Cloud cloud;
  if (Status s = Unpack(msg.xyz(), "xyz", cloud.points); !s.ok()) return s.error();
  if (!msg.normals().empty()) {
    if (msg.normals().size() != msg.xyz().size())
      return invalid_argument("normals has " + std::to_string(msg.normals().size()) + " bytes; xyz has " +
                              std::to_string(msg.xyz().size()) + " and they must match");
    Points normals;  // validated only: core estimates its own normals
    if (Status s = Unpack(msg.normals(), "normals", normals); !s.ok()) return s.error();
  }
  if (msg.has_sensor()) {
    Vec3 sensor(msg.sensor().x(), msg.sensor().y(), msg.sensor().z());
    if (!sensor.allFinite()) return invalid_argument("sensor position is not finite");
    if (sensor.cwiseAbs().maxCoeff() > kMaxAbsCoordinateM)
      return invalid_argument("sensor position has a coordinate beyond +-1e6 m (clouds are in metres)");
    cloud.sensor = sensor;
  }
  return cloud;
}

std::string PackPoints(const Points& points) {
  std::string out;
  out.reserve(points.size() * kBytesPerPoint);
  for (const Vec3& p : points)
    for (int k = 0; k < 3; ++k) AppendFloatLE(out, p[k]);
  return out;
}

v1::PointCloud CloudToProto(const Cloud& cloud) {
  v1::PointCloud msg;
  msg.set_xyz(PackPoints(cloud.points));
  if (cloud.sensor) {
    msg.mutable_sensor()->set_x((*cloud.sensor)[0]);
    msg.mutable_sensor()->set_y((*cloud.sensor)[1]);
    msg.mutable_sensor()->set_z((*cloud.sensor)[2]);
  }
  return msg;
}

Expected<std::optional<MethodId>> MethodFromProto(int method) {
  if (method == v1::METHOD_UNSPECIFIED) return std::optional<MethodId>();
  if (!v1::Method_IsValid(method))
    return invalid_argument("unknown method " + std::to_string(method) +
                            "; valid: METHOD_BOK, METHOD_BOG, METHOD_KGH, METHOD_VFH, METHOD_ESF, METHOD_FUSION, METHOD_USH, METHOD_SIZE");
  return std::optional<MethodId>(static_cast<MethodId>(method - 1));  // the enums differ by UNSPECIFIED
}

v1::Method MethodToProto(MethodId method) { return static_cast<v1::Method>(static_cast<int>(method) + 1); }

Status ValidateModelName(std::string_view name) {
  if (name.empty()) return invalid_argument("model name is empty");
  if (name.size() > kMaxNameLength)
    return invalid_argument("model name is longer than " + std::to_string(kMaxNameLength) + " characters");
  for (char c : name) {
    bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
              c == '_' || c == '-';
    if (!ok) return invalid_argument("model name may only contain A-Z a-z 0-9 . _ -");
  }
  return {};
}

Expected<TrainSpec> TrainSpecFromProto(const v1::TrainHeader& header) {
  if (Status s = ValidateModelName(header.model_name()); !s.ok()) return s.error();
  if (header.description().size() > kMaxDescriptionBytes)
    return invalid_argument("description is longer than " + std::to_string(kMaxDescriptionBytes) + " bytes");
  TrainSpec spec;
  for (int m : header.methods()) {
    auto method = MethodFromProto(m);
    if (!method) return method.error();
    if (!*method) return invalid_argument("methods: METHOD_UNSPECIFIED is not a method");
    spec.methods.push_back(**method);
  }
  auto default_method = MethodFromProto(header.default_method());
  if (!default_method) return default_method.error();
  spec.default_method = *default_method;
  if (spec.default_method && !spec.methods.empty() &&
      std::find(spec.methods.begin(), spec.methods.end(), *spec.default_method) == spec.methods.end())
    return invalid_argument("default_method is not one of the methods to train");
  const v1::TrainParameters& p = header.parameters();
  if (p.has_support_radius_m() && !(std::isfinite(p.support_radius_m()) && p.support_radius_m() >= 0))
    return invalid_argument("support_radius_m must be a finite number >= 0 (0: automatic)");
  auto positive = [](bool has, uint32_t v, const char* field) -> Status {
    if (has && v == 0) return invalid_argument(std::string(field) + " must be positive");
    return {};
  };
  for (Status s : {positive(p.has_bok_codebook_size(), p.bok_codebook_size(), "bok_codebook_size"),
                   positive(p.has_bog_keypoint_clusters(), p.bog_keypoint_clusters(), "bog_keypoint_clusters"),
                   positive(p.has_bog_volume_clusters(), p.bog_volume_clusters(), "bog_volume_clusters"),
                   positive(p.has_bog_pca_dims(), p.bog_pca_dims(), "bog_pca_dims"),
                   positive(p.has_kgh_keypoint_clusters(), p.kgh_keypoint_clusters(), "kgh_keypoint_clusters"),
                   positive(p.has_kgh_distance_bins(), p.kgh_distance_bins(), "kgh_distance_bins"),
                   positive(p.has_centres_per_category(), p.centres_per_category(), "centres_per_category"),
                   positive(p.has_neighbours(), p.neighbours(), "neighbours")})
    if (!s.ok()) return s.error();
  if (!v1::DecisionKind_IsValid(p.decision())) return invalid_argument("unknown decision kind");
  spec.parameters = p;
  return spec;
}

void ToProto(const ModelRecord& r, v1::ModelInfo* out) {
  out->set_id(static_cast<uint64_t>(r.id));
  out->set_name(r.name);
  out->set_version(r.version);
  out->set_is_default(r.is_default);
  out->mutable_created()->set_seconds(r.created_unix_ms / 1000);
  out->mutable_created()->set_nanos(static_cast<int32_t>(r.created_unix_ms % 1000) * 1'000'000);
  out->set_description(r.description);
  for (MethodId m : r.methods) out->add_methods(MethodToProto(m));
  out->set_default_method(MethodToProto(r.default_method));
  for (const std::string& c : r.stats.categories) out->add_categories(c);
  if (!r.params.empty()) {
    // Stored by this server from a valid message; unknown fields (a newer server's) are skipped.
    google::protobuf::util::JsonParseOptions options;
    options.ignore_unknown_fields = true;
    (void)google::protobuf::util::JsonStringToMessage(r.params, out->mutable_parameters(), options);
  }
  v1::TrainingStats* stats = out->mutable_stats();
  stats->set_clouds(r.stats.clouds);
  stats->set_objects(r.stats.objects);
  stats->set_keypoints(r.stats.keypoints);
  stats->set_seconds(r.stats.seconds);
  for (size_t i = 0; i < r.stats.categories.size(); ++i) {
    v1::CategoryCount* c = stats->add_categories();
    c->set_category(r.stats.categories[i]);
    if (i < r.stats.clouds_per_category.size()) c->set_clouds(r.stats.clouds_per_category[i]);
  }
  out->set_size_bytes(r.size_bytes);
  out->set_sha256(r.sha256);
  out->set_feature_version(r.feature_version);
  out->set_min_extent_m(r.stats.min_extent_m);
  out->set_max_extent_m(r.stats.max_extent_m);
}

namespace {
template <class Msg>
void AddScores(const std::vector<std::string>& categories, const std::vector<double>& scores, int winner, Msg* out) {
  for (size_t i = 0; i < categories.size(); ++i) {
    v1::CategoryScore* s = out->add_scores();
    s->set_category(categories[i]);
    s->set_score(i < scores.size() ? scores[i] : 0.0);
  }
  const bool decided = winner >= 0 && static_cast<size_t>(winner) < categories.size();
  out->set_winner_index(decided ? winner : -1);
  out->set_winner(decided ? categories[static_cast<size_t>(winner)] : std::string());
}
}  // namespace

void ToProto(const Classification& c, v1::ClassifyResponse* out) {
  out->set_method(MethodToProto(c.method));
  AddScores(c.categories, c.scores, c.winner, out);
  out->set_points(c.points);
  out->set_keypoints(c.keypoints);
  out->mutable_timings()->set_feature_ms(c.feature_ms);
  out->mutable_timings()->set_decision_ms(c.decision_ms);
  out->set_warning(c.warning);
  out->set_unknown(c.unknown);
  if (std::isfinite(c.novelty)) out->set_novelty(c.novelty);
  out->set_unknown_reason(c.unknown_reason);
}

void ToProto(const StreamDecision& d, v1::Decision* out) {
  out->set_chunk_index(d.chunk_index);
  out->set_points(d.points);
  out->set_keypoints(d.keypoints);
  AddScores(d.categories, d.scores, d.winner, out);
  if (d.raw_scores.size() == d.categories.size())
    for (size_t i = 0; i < d.categories.size(); ++i) {
      v1::CategoryScore* s = out->add_raw_scores();
      s->set_category(d.categories[i]);
      s->set_score(d.raw_scores[i]);
    }
  out->set_final(d.final);
  out->set_category_changes(static_cast<uint32_t>(std::max(0, d.category_changes)));
  out->set_winner_held_chunks(static_cast<uint32_t>(std::max(0, d.winner_held_chunks)));
  out->set_settled(d.settled);
  out->set_confidence(d.confidence);
  out->set_unknown(d.unknown);
  if (std::isfinite(d.novelty)) out->set_novelty(d.novelty);
  out->set_unknown_reason(d.unknown_reason);
}

Expected<double> KnownAcceptanceFromProto(double known_acceptance) {
  if (known_acceptance >= 0 && known_acceptance <= 1) return known_acceptance;
  return invalid_argument("known_acceptance must be in (0, 1] (0: the model's default), not " +
                          std::to_string(known_acceptance));
}

grpc::Status ToGrpcStatus(const Error& error, bool deadline_exceeded) {
  switch (error.code) {
    case ErrorCode::kInvalidArgument: return {grpc::StatusCode::INVALID_ARGUMENT, error.message};
    case ErrorCode::kNotFound: return {grpc::StatusCode::NOT_FOUND, error.message};
    case ErrorCode::kResourceExhausted: return {grpc::StatusCode::RESOURCE_EXHAUSTED, error.message};
    case ErrorCode::kFailedPrecondition: return {grpc::StatusCode::FAILED_PRECONDITION, error.message};
    case ErrorCode::kDataLoss: return {grpc::StatusCode::DATA_LOSS, error.message};
    case ErrorCode::kCancelled:
      return deadline_exceeded ? grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, error.message)
                               : grpc::Status(grpc::StatusCode::CANCELLED, error.message);
    case ErrorCode::kInternal: return {grpc::StatusCode::INTERNAL, error.message};
  }
  return {grpc::StatusCode::UNKNOWN, error.message};
}

}  // namespace glimpse::server

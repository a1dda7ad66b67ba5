// ScanSession: incremental features over a growing scan (only neighbourhoods touched by new points are
// recomputed) and an evolving decision that settles from the tendency of its history (sec. 4).
#include "glimpse/session.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "glimpse/features.h"
#include "glimpse/neighbourhoods.h"
#include "glimpse/preprocess.h"
#include "glimpse/surface_fit.h"
#include "glimpse/keypoints.h"
#include "glimpse/upright_histogram.h"
#include "model_impl.h"

namespace glimpse {

namespace {

class Session final : public ScanSession {
 public:
  Session(std::shared_ptr<const Model> model, const SessionParams& params, Method method)
      : model_(std::move(model)), impl_(*model_->impl), params_(params), method_(method),
        components_(component_methods(impl_, method)) {
    if (const Calibration& c = impl_.calibration;
        params_.use_model_calibration && c.method == method_ && c.settle_margin > 0 && params_.settle_confidence > 0)
      params_.full_margin = c.settle_margin / params_.settle_confidence;
    last_.categories = model_->categories;
    last_.scores.assign(model_->categories.size(), 0.0);
    for (Method m : components_) {
      needs_keypoints_ = needs_keypoints_ || uses_keypoints(m);
      needs_global_ = needs_global_ || !uses_keypoints(m);
    }
  }

  Expected<Decision> add(const Cloud& chunk) override;
  const Decision& last() const override { return last_; }

 private:
  Status check(const Cloud& chunk) const;
  void fix_support_radius();
  std::vector<uint32_t> insert(const Points& points, const std::optional<Vec3>& sensor);
  void update_surfaces(const std::vector<uint32_t>& added);
  void update_keypoints(const std::vector<uint32_t>& added);
  void update_global();
  void decide();

  std::shared_ptr<const Model> model_;
  const ModelImpl& impl_;
  SessionParams params_;
  Method method_;
  std::vector<Method> components_;
  bool needs_keypoints_ = false, needs_global_ = false;

  size_t chunks_ = 0;
  Cloud pending_;                                  // points kept until r can be fixed
  std::vector<std::optional<Vec3>> pending_views_;
  float r_ = 0;
  std::unique_ptr<VoxelIndex> index_;
  std::vector<std::optional<Vec3>> viewpoint_;     // per point: the sensor of the chunk it came in
  std::optional<Vec3> sensor_;                     // the latest sensor position
  std::vector<LocalSurface> surfaces_;
  BoundaryMemo memo_;
  std::vector<Keypoint> keypoints_;
  std::vector<std::optional<Descriptor>> descriptor_of_;  // per point, for keypoints; reset when touched
  CloudFeatures features_;
  size_t global_at_points_ = 0;
  std::vector<uint32_t> epoch_;  // scratch marks for "already collected"
  uint32_t epoch_now_ = 0;

  DecisionTrack track_;
  Decision last_;
};

Status Session::check(const Cloud& chunk) const {
  if (chunks_ >= params_.max_chunks)
    return resource_exhausted("the session reached its limit of " + std::to_string(params_.max_chunks) + " chunks");
  if (chunk.points.size() > params_.max_chunk_points)
    return resource_exhausted("a chunk of " + std::to_string(chunk.points.size()) + " points exceeds the limit of " +
                              std::to_string(params_.max_chunk_points));
  for (size_t i = 0; i < chunk.points.size(); ++i) {
    if (!chunk.points[i].allFinite())
      return invalid_argument("point " + std::to_string(i) + " of chunk " + std::to_string(chunks_) + " is not finite");
    if (chunk.points[i].cwiseAbs().maxCoeff() > kMaxCoordinateM)
      return invalid_argument("point " + std::to_string(i) + " of chunk " + std::to_string(chunks_) +
                              " lies beyond " + std::to_string(int(kMaxCoordinateM)) + " m of the origin");
  }
  if (chunk.sensor && !chunk.sensor->allFinite()) return invalid_argument("the chunk's sensor position is not finite");
  const size_t have = (index_ ? index_->points().size() : 0) + pending_.points.size();
  if (have >= params_.max_points)
    return resource_exhausted("the session holds " + std::to_string(have) + " points, its limit is " +
                              std::to_string(params_.max_points));
  return {};
}

// r is fixed once, from the density of the first points, exactly as extract() picks it for a cloud.
void Session::fix_support_radius() {
  const FeatureParams& fp = impl_.params.features;
  if (fp.surface.support_radius_m > 0) {
    r_ = fp.surface.support_radius_m;
  } else {
    const Cloud cleaned = clean(pending_, fp.duplicate_tolerance_m);
    const KdTree tree(cleaned.points);
    r_ = support_radius(tree, fp.surface);
  }
  if (!(r_ > 0)) return;
  index_ = std::make_unique<VoxelIndex>(r_);
}

std::vector<uint32_t> Session::insert(const Points& points, const std::optional<Vec3>& sensor) {
  std::vector<uint32_t> added;
  std::vector<Neighbour> near;
  const float duplicate = impl_.params.features.duplicate_tolerance_m;
  for (const Vec3& p : points) {
    if (index_->points().size() >= params_.max_points) break;
    index_->radius(p, duplicate, near);
    if (!near.empty()) continue;  // a duplicate (overlapping chunks, re-sent points)
    added.push_back(index_->add(p));
    viewpoint_.push_back(sensor);
  }
  return added;
}

void Session::update_surfaces(const std::vector<uint32_t>& added) {
  const size_t n = index_->points().size();
  surfaces_.resize(n);
  descriptor_of_.resize(n);
  epoch_.resize(n, 0);
  ++epoch_now_;
  // Every point within r of a new point has a new neighbourhood.
  std::vector<uint32_t> touched;
  std::vector<Neighbour> near;
  for (uint32_t i : added) {
    index_->radius(index_->points()[i], r_, near);
    for (const Neighbour& q : near)
      if (epoch_[q.index] != epoch_now_) {
        epoch_[q.index] = epoch_now_;
        touched.push_back(q.index);
      }
  }
  std::sort(touched.begin(), touched.end());
  const int min_neighbours = impl_.params.features.surface.min_neighbours;
  memo_.boundary.resize(n, -1);
  memo_.touches_boundary.resize(n, -1);
  for (uint32_t i : touched) {
    const LocalSurface before = surfaces_[i];
    surfaces_[i] = local_surface(*index_, i, r_, viewpoint_[i], min_neighbours, near);
    LocalSurface& s = surfaces_[i];
    if (s.valid && !viewpoint_[i]) {
      // No sensor: keep the sign the point had, else agree with the nearest oriented neighbour.
      Vec3 ref = before.valid ? before.normal : Vec3::Zero();
      if (ref.isZero())
        for (const Neighbour& q : near)
          if (q.index != i && surfaces_[q.index].valid) {
            ref = surfaces_[q.index].normal;
            break;
          }
      if (!ref.isZero() && s.normal.dot(ref) < 0) {
        s.normal = -s.normal;
        const float k1 = s.k1;
        s.k1 = -s.k2;
        s.k2 = -k1;
      }
    }
    // Its boundary status may have changed, and so may "touches a boundary" of its neighbours.
    memo_.boundary[i] = -1;
    for (const Neighbour& q : near) memo_.touches_boundary[q.index] = -1;
  }
  // Descriptors read normals up to 2r away and the large window (R) around the keypoint.
  const float reach = std::max(2.f, impl_.params.features.descriptor.large_window_supports) * r_;
  for (uint32_t i : added) {
    index_->radius(index_->points()[i], reach, near);
    for (const Neighbour& q : near) descriptor_of_[q.index].reset();
  }
}

void Session::update_keypoints(const std::vector<uint32_t>&) {
  KeypointStats stats;
  keypoints_ = characteristic_scale_keypoints(*index_, surfaces_, r_, impl_.params.features.keypoints, &stats, &memo_);
  features_.positions.clear();
  features_.descriptors.clear();
  std::vector<Neighbour> scratch;
  for (const Keypoint& k : keypoints_) {
    auto& cached = descriptor_of_[k.index];
    if (!cached) cached = local_descriptor(*index_, surfaces_, k, r_, impl_.params.features.descriptor, scratch);
    features_.positions.push_back(k.position);
    features_.descriptors.push_back(*cached);
  }
}

void Session::update_global() {
  const size_t n = index_->points().size();
  // USH is one pass over the surfaces already kept up to date: cheap enough for every chunk.
  if (std::find(components_.begin(), components_.end(), Method::kUSH) != components_.end())
    features_.ush = upright_histogram(index_->points(), surfaces_, impl_.params.ush);
  if (global_at_points_ && static_cast<double>(n) < (1.0 + params_.global_refresh_growth) * static_cast<double>(global_at_points_))
    return;
  Cloud cloud{index_->points(), sensor_};
  for (Method m : components_) {
    if (m == Method::kVFH) {
      auto v = vfh(cloud, impl_.params.global);
      if (v.ok()) features_.vfh = std::move(*v);
    } else if (m == Method::kESF) {
      auto e = esf(cloud, impl_.params.seed);
      if (e.ok()) features_.esf = std::move(*e);
    }
  }
  global_at_points_ = n;
}

void Session::decide() {
  const Eigen::VectorXd scores = method_scores(impl_, method_, features_);
  track_.decision.chunk_index = last_.chunk_index;
  track_decision(track_, std::vector<double>(scores.data(), scores.data() + scores.size()), keypoints_.size(),
                 needs_keypoints_, params_);
  const Decision& d = track_.decision;
  last_.scores = d.scores;
  last_.winner = d.winner;
  last_.category_changes = d.category_changes;
  last_.winner_held_chunks = d.winner_held_chunks;
  last_.confidence = d.confidence;
  last_.settled = d.settled;
}

Expected<Decision> Session::add(const Cloud& chunk) {
  if (Status s = check(chunk); !s.ok()) return s.error();
  last_.chunk_index = chunks_++;
  if (chunk.sensor) sensor_ = chunk.sensor;
  std::vector<uint32_t> added;
  if (!index_) {
    // Points beyond the session's limit are not kept (the next chunk is refused).
    const size_t room = params_.max_points - std::min(params_.max_points, pending_.points.size());
    const size_t take = std::min(room, chunk.points.size());
    pending_.points.insert(pending_.points.end(), chunk.points.begin(), chunk.points.begin() + static_cast<std::ptrdiff_t>(take));
    pending_views_.insert(pending_views_.end(), take, chunk.sensor);
    last_.points = pending_.points.size();
    if (pending_.points.size() < params_.min_points_for_radius) return last_;  // nothing to decide on yet
    fix_support_radius();
    if (!index_) return last_;  // all points coincide so far
    // The pending points arrive as one batch, each with the sensor of its own chunk.
    for (size_t i = 0; i < pending_.points.size(); ++i) {
      auto part = insert({pending_.points[i]}, pending_views_[i]);
      added.insert(added.end(), part.begin(), part.end());
    }
    pending_ = {};
    pending_views_.clear();
  } else {
    added = insert(chunk.points, chunk.sensor);
  }
  last_.points = index_->points().size();
  if (!added.empty()) {
    update_surfaces(added);
    if (needs_keypoints_) update_keypoints(added);
    if (needs_global_) update_global();
  }
  last_.keypoints = keypoints_.size();
  decide();
  return last_;
}

}  // namespace

void track_decision(DecisionTrack& t, const std::vector<double>& scores, size_t keypoints, bool keypoints_matter,
                    const SessionParams& params) {
  Decision& d = t.decision;
  if (t.smoothed.size() != scores.size()) t.smoothed = scores;
  else
    for (size_t i = 0; i < scores.size(); ++i) t.smoothed[i] = params.smoothing * scores[i] + (1 - params.smoothing) * t.smoothed[i];
  int winner = -1;
  for (size_t i = 0; i < t.smoothed.size(); ++i)
    if (winner < 0 || t.smoothed[i] > t.smoothed[static_cast<size_t>(winner)]) winner = static_cast<int>(i);
  const bool was_settled = d.settled && winner == d.winner;
  if (d.winner >= 0 && winner != d.winner) ++d.category_changes;
  d.winner_held_chunks = winner == d.winner ? d.winner_held_chunks + 1 : 1;
  d.winner = winner;
  d.scores = t.smoothed;
  t.winners.push_back(winner);

  // Confidence from the tendency of the history: the margin between the best two smoothed scores,
  // times the share of the recent decisions the winner won.
  std::vector<double> sorted(t.smoothed);
  std::sort(sorted.rbegin(), sorted.rend());
  const double margin = sorted.size() > 1 ? sorted[0] - sorted[1] : 1.0;
  const size_t window = static_cast<size_t>(std::max(1, params.stability_window));
  const size_t from = t.winners.size() > window ? t.winners.size() - window : 0;
  const auto held = std::count(t.winners.begin() + static_cast<std::ptrdiff_t>(from), t.winners.end(), winner);
  const double stability = static_cast<double>(held) / static_cast<double>(window);
  d.confidence = std::clamp(margin / params.full_margin, 0.0, 1.0) * stability;
  const bool enough = !keypoints_matter || keypoints >= params.min_keypoints;
  const double needed = was_settled ? params.settle_confidence - params.unsettle_margin : params.settle_confidence;
  d.settled = enough && d.confidence >= needed;
}

Expected<std::unique_ptr<ScanSession>> ScanSession::create(std::shared_ptr<const Model> model,
                                                            const SessionParams& params) {
  if (!model || !model->impl) return failed_precondition("the session needs a trained model");
  if (Status s = check_feature_version(*model); !s.ok()) return s.error();
  const Method method = params.method.value_or(model->default_method);
  if (std::find(model->methods.begin(), model->methods.end(), method) == model->methods.end())
    return invalid_argument(std::string("the model was not trained for method '") + method_name(method) + "'");
  if (params.max_points == 0 || params.max_chunks == 0 || params.max_chunk_points == 0)
    return invalid_argument("session limits must be positive");
  return std::unique_ptr<ScanSession>(std::make_unique<Session>(std::move(model), params, method));
}

}  // namespace glimpse

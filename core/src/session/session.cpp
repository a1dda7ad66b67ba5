// ScanSession: a growing scan's feature state (ScanFeatures, the state extract() gives the points so
// far) and an evolving decision that settles from the tendency of its history (sec. 4).
#include "glimpse/session/session.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include "glimpse/features/local_features.h"
#include "glimpse/geometry/clean.h"
#include "glimpse/geometry/scan_filters.h"
#include "glimpse/learning/classify.h"
#include "glimpse/learning/model_internals.h"
#include "glimpse/learning/novelty.h"
#include "glimpse/learning/probabilities.h"
#include "glimpse/learning/scores.h"

namespace glimpse {

namespace {

class Session final : public ScanSession {
 public:
  Session(std::shared_ptr<const Model> model, const SessionParams& params, MethodId method)
      : model_(std::move(model)), impl_(*model_->impl), params_(params), method_(method),
        components_(component_methods(impl_, method)), method_params_(feature_params_for(impl_, method)),
        features_(feature_params()),
        duplicates_(impl_.params.features.duplicate_tolerance_m) {
    if (const Calibration& c = impl_.calibration;
        params_.use_model_calibration && c.method == method_ && c.settle_margin > 0 && params_.settle_confidence > 0)
      params_.full_margin = c.settle_margin / params_.settle_confidence;
    if (const Calibration& c = impl_.calibration;
        params_.use_model_calibration && params_.settle_on_probability && c.method == method_ && c.settle_probability > 0) {
      params_.probability_temperature = c.probability_temperature;
      params_.settle_probability = c.settle_probability;
    }
    const Calibration& c = novelty_calibration(impl_);
    threshold_ = c.method == method_ ? novelty_threshold(c, params_.known_acceptance > 0 ? params_.known_acceptance
                                                                                        : c.known_acceptance)
                                     : std::numeric_limits<double>::quiet_NaN();
    last_.categories = model_->categories;
    last_.scores.assign(model_->categories.size(), 0.0);
  }

  Expected<StreamDecision> add(const Cloud& chunk) override;
  Expected<StreamDecision> finish() override;
  const StreamDecision& last() const override { return last_; }

 private:
  FeatureParams feature_params() const {
    FeatureParams fp = impl_.params.features;
    fp.surface.threads = 1;
    fp.find_keypoints = std::any_of(components_.begin(), components_.end(), uses_keypoints);
    return fp;
  }
  Status check(const Cloud& chunk) const;
  // A model that filters its scans (floor, strays, density) judges them on the scan so far, filtered
  // as a whole: a floor, a stray or the density is a property of the whole scan, not of the newest
  // chunk (a top-down scan's last chunk is all floor). See SessionParams::global_refresh_growth for
  // when the filters run and which features then decide a chunk.
  bool filtered() const { return impl_.params.filter_scans; }
  size_t points() const { return filtered() ? raw_.points.size() : features_.points(); }
  void add_raw(const Cloud& chunk);
  // ScanFeatures catch up with the raw points (in their chunks' sensor runs): the points they kept.
  Expected<size_t> feed_features();
  // Classify's of the accumulated points (the last one again when nothing was added since).
  const Expected<Classification>& classify_so_far();
  bool update_method_features(bool whole_cloud_too);
  void decide();
  // Tracks a chunk's evidence (the newest decision's own scores and novelty) through the stability
  // window into last_.
  void track(ChunkEvidence e);

  std::shared_ptr<const Model> model_;
  const ModelImpl& impl_;
  SessionParams params_;
  MethodId method_;
  std::vector<MethodId> components_;
  MethodFeatureParams method_params_;  // what the components' features are computed with (feature_params_for)
  ScanFeatures features_;
  DuplicateFilter duplicates_;                      // filtered(): clean()'s rule on the raw points
  Cloud raw_;                                       // filtered(): the points as sent, cleaned
  std::vector<std::optional<Vec3>> raw_sensors_;    // per raw point: its chunk's sensor
  size_t raw_chunks_ = 0;
  size_t fed_ = 0;                                  // raw points added to features_
  size_t filters_at_ = 0;                           // raw points when the filters last ran
  bool filters_change_ = false;                     // ... and whether they changed the scan
  Expected<Classification> classified_ = failed_precondition("nothing classified yet");
  size_t classified_points_ = 0;
  CloudFeatures method_features_;
  bool have_features_ = false;
  size_t global_at_points_ = 0;
  size_t chunks_ = 0;
  DecisionTrack track_;
  StreamDecision last_;
  double threshold_;               // novelty above it is unknown (NaN: never, the method has no novelty)
  MethodDecision method_decision_;  // of the last decide()
};

Status Session::check(const Cloud& chunk) const {
  if (chunks_ >= params_.max_chunks)
    return resource_exhausted("the session reached its limit of " + std::to_string(params_.max_chunks) + " chunks");
  if (chunk.points.size() > params_.max_chunk_points)
    return resource_exhausted("a chunk of " + std::to_string(chunk.points.size()) + " points exceeds the limit of " +
                              std::to_string(params_.max_chunk_points));
  // A chunk that could take the scan past its limit is refused whole: no point is dropped unsaid.
  if (points() + chunk.points.size() > params_.max_points)
    return resource_exhausted("chunk " + std::to_string(chunks_) + " of " + std::to_string(chunk.points.size()) +
                              " points could take the session past its limit of " + std::to_string(params_.max_points) +
                              " points (it holds " + std::to_string(points()) + ")");
  return check_cloud(chunk, "chunk " + std::to_string(chunks_));
}

// The per-method features of the state: keypoints, USH and size every time; VFH and ESF when the scan
// grew enough since their last computation, or when asked (finish). False while the scan has nothing the
// methods can read (no local surface yet: a line, copies of one point), so nothing is decided.
bool Session::update_method_features(bool whole_cloud_too) {
  const FeatureState& st = features_.state();
  std::vector<MethodId> now, global;
  for (MethodId m : components_) (m == MethodId::kVFH || m == MethodId::kESF ? global : now).push_back(m);
  auto cheap = method_features(st, method_params_, now, 1);
  if (!cheap.ok()) return false;
  CloudFeatures f = std::move(*cheap);
  // The top-down prefix (TrainParams::novelty_prefix) alike: its global descriptors are those of the
  // prefix at their last computation; without them yet it is left out.
  std::optional<CloudFeatures> prefix;
  if (f.top_prefix) prefix = *f.top_prefix;
  auto take_global = [](CloudFeatures& to, const CloudFeatures& from, const std::vector<MethodId>& methods) {
    for (MethodId m : methods) (m == MethodId::kVFH ? to.vfh : to.esf) = m == MethodId::kVFH ? from.vfh : from.esf;
  };
  take_global(f, method_features_, global);
  if (prefix) take_global(*prefix, method_features_.top_prefix ? *method_features_.top_prefix : CloudFeatures{}, global);
  const size_t n = st.cloud.points.size();
  const bool grown = !global_at_points_ || static_cast<double>(n) >= (1.0 + params_.global_refresh_growth) *
                                                                        static_cast<double>(global_at_points_);
  if (!global.empty() && (whole_cloud_too || grown)) {
    for (MethodId m : global) {  // one may fail on a scan still too small for it: it keeps its last value
      auto g = method_features(st, method_params_, {m}, 1);
      if (!g.ok()) continue;
      take_global(f, *g, {m});
      if (prefix && g->top_prefix) take_global(*prefix, *g->top_prefix, {m});
    }
    global_at_points_ = n;
  }
  const bool prefix_complete = prefix && std::all_of(global.begin(), global.end(), [&](MethodId m) {
    return m == MethodId::kVFH ? prefix->vfh.has_value() : prefix->esf.has_value();
  });
  f.top_prefix = prefix_complete ? std::make_shared<const CloudFeatures>(std::move(*prefix)) : nullptr;
  method_features_ = std::move(f);
  have_features_ = true;
  return true;
}

void Session::decide() {
  method_decision_ = method_decision(impl_, method_, method_features_);
  const Eigen::VectorXd& scores = method_decision_.scores;
  ChunkEvidence e;
  e.scores.assign(scores.data(), scores.data() + scores.size());
  e.novelty.assign(method_decision_.novelty.data(), method_decision_.novelty.data() + method_decision_.novelty.size());
  e.keypoints = method_features_.positions.size();
  e.cannot_judge = cannot_judge(method_, components_, method_features_);
  track(std::move(e));
}

// A Classify's answer as a chunk's evidence: its scores and per-category novelty; a cloud the method
// cannot judge is unknown with a NaN novelty and the reason.
ChunkEvidence evidence_of(const Classification& c) {
  ChunkEvidence e;
  e.scores = c.scores;
  e.novelty = c.category_novelty;
  e.keypoints = c.keypoints;
  if (c.unknown && !std::isfinite(c.novelty)) e.cannot_judge = c.unknown_reason;
  return e;
}

void Session::track(ChunkEvidence e) {
  last_.raw_scores = e.scores;
  track_.decision.chunk_index = last_.chunk_index;
  track_decision(track_, e, std::any_of(components_.begin(), components_.end(), uses_keypoints), threshold_, params_);
  const StreamDecision& d = track_.decision;
  last_.scores = d.scores;
  last_.probabilities = calibrated_probabilities(impl_.calibration, method_, last_.scores);
  last_.winner = d.winner;
  last_.category_changes = d.category_changes;
  last_.winner_held_chunks = d.winner_held_chunks;
  last_.confidence = d.confidence;
  last_.settled = d.settled;
  last_.unknown = d.unknown;
  last_.novelty = d.novelty;
  last_.unknown_reason = d.unknown_reason;
}

Expected<StreamDecision> Session::add(const Cloud& chunk) {
  if (Status s = check(chunk); !s.ok()) return s.error();
  last_.chunk_index = chunks_++;
  last_.final = false;
  Expected<size_t> kept = size_t{0};
  if (filtered()) {
    add_raw(chunk);
    last_.points = raw_.points.size();
    // The filters cost what the scan holds: they run again once it grew by global_refresh_growth (as
    // VFH does); in between, a filtered scan's chunks repeat its last decision, an unfiltered one's grow
    // ScanFeatures.
    const size_t n = raw_.points.size();
    if (!filters_at_ || double(n) >= (1.0 + params_.global_refresh_growth) * double(filters_at_)) {
      filters_at_ = n;
      if (scan_views(raw_, raw_sensors_).size() > 1) {
        // Several views: Classify's of the scan view by view (classify_fused), repeated by the chunks
        // until the scan has grown enough to decide it again.
        filters_change_ = true;
        classified_ = classify_fused(*model_, raw_, raw_sensors_, method_);
      } else {
        const auto t0 = std::chrono::steady_clock::now();
        ScanFilterReport report;
        const Cloud scan = filter_scan(raw_, impl_.params.filters, &report);
        // A floor or a thinned density changes what every method sees; a few stray points (1 % at most:
        // a sparse top-down prefix's edge) do not, and the chunk-by-chunk features keep them until
        // finish(), which is Classify's of the filtered scan.
        filters_change_ = report.ground > 0 || report.voxel_m > 0 || double(report.outliers) > 0.01 * double(report.input);
        if (filters_change_) classified_ = decide_after_filters(*model_, raw_, raw_sensors_, &scan, report, method_, t0);
      }
      if (filters_change_) {  // Classify's of the scan
        classified_points_ = n;
        if (!classified_.ok()) return last_;  // undecided: too few points, nothing but floor, a line
        last_.keypoints = classified_->keypoints;
        track(evidence_of(*classified_));
        return last_;
      }
    } else if (filters_change_) {
      return last_;  // the last decision stands until the scan has grown enough to filter it again
    }
    kept = feed_features();
  } else {
    kept = features_.add(chunk);
  }
  if (!kept.ok()) return kept.error();
  last_.points = features_.points();
  if (!features_.ready()) return last_;  // nothing to decide on yet
  if (*kept > 0 || last_.raw_scores.empty()) update_method_features(false);
  if (!have_features_) return last_;  // undecided: nothing to judge yet
  last_.keypoints = method_features_.positions.size();
  decide();
  return last_;
}

void Session::add_raw(const Cloud& chunk) {
  raw_.frame = joined_frame(raw_, chunk, raw_chunks_++ == 0);
  clean_into(chunk, {}, duplicates_, raw_, &raw_sensors_);
  if (chunk.sensor) raw_.sensor = chunk.sensor;
}

Expected<size_t> Session::feed_features() {
  size_t added = 0;
  while (fed_ < raw_.points.size()) {
    Cloud run;
    run.sensor = raw_sensors_[fed_];
    run.frame = raw_.frame;  // none once the sensor moved (joined_frame)
    for (; fed_ < raw_.points.size() && raw_sensors_[fed_] == run.sensor; ++fed_) run.points.push_back(raw_.points[fed_]);
    auto kept = features_.add(run);
    if (!kept.ok()) return kept.error();
    added += *kept;
  }
  return added;
}

const Expected<Classification>& Session::classify_so_far() {
  if (raw_.points.size() != classified_points_ || !classified_.ok()) {
    classified_ = classify_fused(*model_, raw_, raw_sensors_, method_);
    classified_points_ = raw_.points.size();
  }
  return classified_;
}

Expected<StreamDecision> Session::finish() {
  Classification c;
  if (filtered()) {
    // The final decision is Classify's of the accumulated scan (filtered as a whole, each point facing
    // its chunk's sensor): the last chunk's, tracked once more.
    const Expected<Classification>& got = classify_so_far();
    // Classify of the whole scan fails (the filters left too few points): so does the scan, never an
    // answer that is not final.
    if (!got.ok()) return Error{got.error().code, "the whole scan: " + got.error().message};
    last_.points = got->points;
    last_.keypoints = got->keypoints;
    track(evidence_of(*got));
    c = *got;
  } else {
    if (!features_.ready() || (!update_method_features(true) && !have_features_))
      return invalid_argument("the scan ended without a decision: its " + std::to_string(features_.points()) +
                              " points gave no surface to judge (too few, or all on a line)");
    last_.keypoints = method_features_.positions.size();
    decide();
    c.method = method_;
    c.winner = static_cast<int>(std::max_element(last_.raw_scores.begin(), last_.raw_scores.end()) - last_.raw_scores.begin());
    judge_cloud(*model_, method_decision_, method_features_, features_.state().cloud, c);
  }
  // The scan is over: the answer is Classify's of the whole scan (at the session's operating point),
  // not the running average.
  (void)set_known_acceptance(*model_, c, params_.known_acceptance);  // checked by create()
  last_.scores = last_.raw_scores;
  last_.probabilities = calibrated_probabilities(impl_.calibration, method_, last_.scores);
  const int before = track_.winners.empty() ? -1 : track_.winners.back();
  const int now = c.unknown ? static_cast<int>(last_.scores.size()) : c.winner;
  if (before >= 0 && now != before) {  // the running average had not caught up: not settled on it
    ++last_.category_changes;
    last_.winner_held_chunks = 1;
    last_.settled = false;
    last_.confidence = 0;
  }
  last_.winner = c.winner;
  last_.unknown = c.unknown;
  last_.novelty = c.novelty;
  last_.unknown_reason = c.unknown_reason;
  last_.frame_cut = c.frame_cut;
  last_.final = true;
  return last_;
}

}  // namespace

Expected<std::unique_ptr<ScanSession>> ScanSession::create(std::shared_ptr<const Model> model,
                                                            const SessionParams& params) {
  if (!model || !model->impl) return failed_precondition("the session needs a trained model");
  if (Status s = check_feature_version(*model); !s.ok()) return s.error();
  const MethodId method = params.method.value_or(model->default_method);
  if (Status s = check_trained_for(*model, method); !s.ok()) return s.error();
  if (params.max_points == 0 || params.max_chunks == 0 || params.max_chunk_points == 0)
    return invalid_argument("session limits must be positive");
  if (!(params.known_acceptance >= 0 && params.known_acceptance <= 1))
    return invalid_argument("known acceptance must be in (0, 1] (0: the model's default), not " +
                            std::to_string(params.known_acceptance));
  return std::unique_ptr<ScanSession>(std::make_unique<Session>(std::move(model), params, method));
}

}  // namespace glimpse

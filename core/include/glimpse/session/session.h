// ScanSession: a remote scanner streams an object piece by piece; the session fuses the chunks,
// updates features incrementally and answers each chunk with an evolving StreamDecision (sec. 4).
#pragma once

#include <cstddef>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/learning/model.h"

namespace glimpse {

struct SessionParams {
  std::optional<MethodId> method;      // default: the model's default method
  // Limits: a session never grows without bound (errors: resource exhausted).
  size_t max_points = 1'000'000;     // accumulated (after duplicate removal)
  size_t max_chunks = 10'000;
  size_t max_chunk_points = 200'000;
  // A model that filters its scans (TrainParams::filter_scans, the default) runs its filters on the
  // accumulated points when the scan grew by global_refresh_growth since they last ran (and on the
  // first chunk with enough points). When they change the scan (a floor, more than 1 % stray returns,
  // a density above the trained one), or when the scan holds several views (sensors looking from more
  // than 30 degrees apart), that chunk is decided by Classify's of the scan (classify_fused: view by
  // view, each point facing its chunk's sensor; about 0.4 s for 670k points of six 640x480 depth frames with
  // their floor), and the chunks until the next run repeat that decision. Otherwise, and for
  // a model without filters, the features are ScanFeatures' (features/local_features.h): the state
  // extract() gives the accumulated points, grown incrementally, duplicates by the rule of clean(). VFH and ESF
  // describe the whole cloud and cost what it holds, so on this path they are recomputed when the
  // scan grew by this fraction since the last time and always by finish(); USH and size every chunk.
  double global_refresh_growth = 0.2;
  // Settling (sec. 4, "the decision is consolidating"): confidence combines the winner's calibrated
  // probability (or, for a model without probabilities, the margin between the best two smoothed
  // scores) and how steadily the winner held over the last decisions.
  double smoothing = 0.5;            // weight of the newest scores in the running average
  int stability_window = 4;          // decisions the stability looks back on
  // Smoothed margin giving full margin confidence. A model calibrated on held-out folds of its training
  // set (its settle margin m, see TrainParams::settle_precision) replaces it by m / settle_confidence,
  // so its decisions settle where they were found right, unless use_model_calibration is false.
  double full_margin = 0.3;
  bool use_model_calibration = true;
  // Settled at or above this, once the winner has won each of the last stability_window decisions,
  // the newest chunk's own raw scores included (a single lucky chunk never settles); "unknown" likewise
  // needs the newest chunk's own novelty above the threshold.
  double settle_confidence = 0.5;
  // A settled decision stays settled while its winner holds and its confidence stays within this of
  // settle_confidence: more of the object narrows the margin a little (the top of a human and of a
  // four-legged animal look alike less than their whole), which must not make the answer flicker.
  double unsettle_margin = 0.2;
  // A model with calibrated probabilities states a category's confidence in them: the probability of
  // the smoothed scores' winner times the share of the last stability_window decisions it won, settling
  // at settle_probability (and staying settled above settle_probability - unsettle_margin) under the
  // same conditions. The session copies both from the model (Calibration::probability_temperature and
  // settle_probability: where held-out decisions were settle_precision right) unless
  // use_model_calibration or settle_on_probability is false. Either 0: the margin rule above.
  bool settle_on_probability = true;
  double settle_probability = 0;
  double probability_temperature = 0;
  size_t min_keypoints = 10;         // keypoint methods never settle on fewer keypoints
  // "None of these": the operating point, the share of known clouds accepted (held out in training;
  // in (0, 1], 0: the model's default). "Unknown" settles as a category does, its margin being how far
  // the smoothed novelty is above the threshold: this fraction of the threshold above it gives full
  // margin confidence.
  double known_acceptance = 0;
  double unknown_full_excess = 0.5;
  // Settling is cautious both ways, so that a settled answer is one a caller can act on. "Unknown"
  // settles only once each of the last unknown_settle_window decisions was unknown and its confidence
  // reached unknown_settle_confidence (a known object from another collection looks novel while little
  // of it is seen). A category settles only while the winner's smoothed novelty is at most
  // settle_novelty_share of the threshold (an object of no learnt category is decided as its nearest
  // one, just inside the threshold, more often than a known one). Chosen on streams the recogniser is
  // not reported on (docs/open-set.md, "In a stream"): SHREC CV with chairs and with quadrupeds held out as unknown,
  // and SHREC and PSB models streaming the zoo.
  int unknown_settle_window = 6;
  double unknown_settle_confidence = 1.0;
  double settle_novelty_share = 0.8;
};

struct StreamDecision {
  size_t chunk_index = 0;           // 0-based index of the chunk this answers (finish: the last one's)
  size_t points = 0;                // accumulated, after duplicate removal
  size_t keypoints = 0;
  std::vector<std::string> categories;
  std::vector<double> scores;       // one per category, in [0, 1]: smoothed over the chunks so far
                                    // (final: Classify's scores of the whole scan)
  std::vector<double> raw_scores;   // this chunk's own scores (after finish: Classify's of the cloud)
  // `scores` as calibrated probabilities (Classification::probabilities; final: Classify's); empty: the
  // model has none for the session's method.
  std::vector<double> probabilities;
  bool final = false;               // the answer of finish(): every feature of the whole scan
  int winner = -1;                  // -1 while there is nothing to decide on
  int category_changes = 0;         // how often the winner changed so far
  int winner_held_chunks = 0;       // consecutive chunks the current winner has held
  bool settled = false;
  double confidence = 0;            // in [0, 1]
  // "None of these": unknown when the winner's novelty (smoothed like the scores; final: Classify's) is
  // above the operating point's threshold, or when the method cannot judge the scan (the reason says
  // which). The winner stays the nearest known category. Changes, held chunks, confidence and settled
  // count "unknown" as one more category. NaN novelty: not calibrated, or cannot judge.
  bool unknown = false;
  double novelty = std::numeric_limits<double>::quiet_NaN();
  std::string unknown_reason;
  FrameCut frame_cut;  // final decision only: the edges of the camera's frame the scan reaches (Classification)
};

// How many decisions in a row must be "unknown" before "unknown" settles: the longer of the stability
// window and unknown_settle_window (at least 1).
size_t unknown_settle_chunks(const SessionParams& params);

// The evolving decision on its own (a pure function of the score history, so it can be scripted):
// each call folds one chunk's scores (and novelties) into the running average and updates winner,
// unknown, changes, held chunks, confidence and settled. `keypoints_matter`: the method needs
// keypoints, so fewer than params.min_keypoints never settle.
struct DecisionTrack {
  std::vector<double> smoothed;
  std::vector<double> smoothed_novelty;  // per category
  std::vector<int> winners;  // every decision's winner so far; unknown counts as category n (one more)
  StreamDecision decision;
};
// What one chunk's decision rests on.
struct ChunkEvidence {
  std::vector<double> scores;
  std::vector<double> novelty;  // per category; empty: not calibrated
  size_t keypoints = 0;
  std::string cannot_judge;     // why the method cannot judge the chunk at all; empty: it can
};
void track_decision(DecisionTrack& track, const ChunkEvidence& chunk, bool keypoints_matter,
                    double novelty_threshold, const SessionParams& params);
// Scores only (no novelty: never unknown).
void track_decision(DecisionTrack& track, const std::vector<double>& scores, size_t keypoints,
                    bool keypoints_matter, const SessionParams& params);

class ScanSession {
 public:
  static Expected<std::unique_ptr<ScanSession>> create(std::shared_ptr<const Model> model,
                                                       const SessionParams& params = {});
  virtual ~ScanSession() = default;
  // Adds a chunk (points in the session's common frame) and returns the updated decision.
  virtual Expected<StreamDecision> add(const Cloud& chunk) = 0;
  // The scanner is done: every feature brought up to date on the whole scan (VFH and ESF too), so the
  // raw scores are Classify's of the accumulated cloud, and the final decision's scores and winner are
  // those raw scores and their argmax (Classify's answer), not the running average. Where Classify of
  // the whole scan fails (too few points, after the filters), finish fails with its error.
  virtual Expected<StreamDecision> finish() = 0;
  virtual const StreamDecision& last() const = 0;
};

}  // namespace glimpse

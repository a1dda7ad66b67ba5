// What the eval subcommand's pieces share: its flags, the progress bar, list parsing, the objects it
// runs on (eval_objects.cpp) and the ablations run beside the main evaluation (ablations.cpp).
#pragma once

#include <unistd.h>

#include <chrono>
#include <functional>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "glimpse/lab/evaluation.h"

namespace glimpse::lab {

// Every flag of glimpse-lab eval (eval.cpp declares them); negative numbers and empty strings: not given.
struct EvalOptions {
  std::string data;
  std::string train;
  std::string test;
  std::string size_blind = "fusion";
  std::string also_train;
  std::string unknown;  // --unknown: objects of categories no model learns
  std::string leave_one_out;  // --leave-one-out: sources each tested by a model of the others
  std::string hold_out;  // --hold-out: categories of the evaluated sources no model learns, tested as unknown
  float tilt = -1;
  size_t zoo = 0;
  std::string points = "6000";
  size_t views = 6;
  int folds = 5;
  std::string methods = "bok,bog,kgh,vfh,esf,ush,size,fusion";
  std::string train_on = "partial";
  std::string train_prefixes = "0.15,0.25,0.35,0.5,0.7";
  std::string train_elevations;  // extra training-only views, degrees above the horizon
  std::string train_sensors;     // extra training-only views of simulated sensors: SENSOR:METRES:DEGREES,...
  std::string decision = "nearest";
  std::string fusion_of;
  double fusion_head_c = -1;  // < 0: the recogniser's; 0: no logistic decision in the fusion
  int fusion_head_rows = -1;  // < 0: the recogniser's; 0: every row
  std::string augmented_prefixes;  // "on", "off"; empty: the recogniser's
  int neighbours = 0;
  double pca_variance = 0;
  int pca_dims = 0;
  int threads = 0;
  uint64_t seed = 42;
  std::string out = "out/eval";
  bool quick = false;
  size_t max_objects = 0;
  size_t pick_objects = 0;         // N objects per category drawn by the seed (0: all)
  size_t objects_per_category = 0; // few-shot: each model learns at most K objects per category (0: all)
  std::string export_histograms;   // folder: every fold model's histograms as CSV (EvalParams::export_histograms_dir)
  std::string poses = "dataset";   // dataset: categories without a natural up in a random pose; given: as the file has it
  size_t explore_step = 5;
  float cut_margin = 1.5f;
  std::string stages = "full,10kp,25kp,55kp,10%,20%";
  double stream_chunk = 0.02;
  std::string sensor = "ideal";
  float distance = 2.f;
  float elevation = 30.f;
  float scan_tilt = 0.f;
  bool floor = false;
  double outliers = 0;
  std::string matrix = "small";
  std::string preset;
  // Keypoints (sec. 2.2, 3.2.1-3.2.2); negative: the recogniser's default.
  int support_neighbours = -1;
  int min_neighbours = -1;
  float keypoint_cap = -1;     // rho1 cap in support radii, 0: none
  float claim_min = -1;        // claim radius at least this x r, 0: rho1 alone
  float boundary_band = -1;    // in support radii, 0: boundary points only
  float boundary_gap = -1;     // degrees
  float boundary_radius = -1;  // the boundary test's neighbourhood, in support radii
  float descriptor_scale = -1; // descriptors over rho1 clamped to [r, this x r]; 0: over r
  std::string keypoint_response;
  int normalise_up_to = -1;
  std::string default_method;
  bool keypoint_ablation = false;
  int soft_words = 0;
  size_t matrix_views = 0;  // 0: 1 per object for the small matrix (the default run stays within 5 minutes), 2 for full and sensors
};

// --preset paper: the paper's settings for every flag `given` says is not on the command line
// (eval_params.cpp).
Status apply_preset(EvalOptions& o, const std::function<bool(const char* flag)>& given);
// The flags as the protocol's parameters; errors name the flag and what it takes.
Expected<EvalParams> params_from(const EvalOptions& o);

// A source named twice (its objects learnt twice, or learnt and cross-validated at once) is an error;
// --train X --test X is not (resubstitution, which the report flags).
Status check_sources(const EvalOptions& o);
// The objects the flags name, with their roles, drawn (--pick-objects) and held out (--hold-out), into
// `objects`; `source` says where they come from, for the report. 0, or the exit code once the reason is
// printed (1: a source failed to load; 2: the flags ask for figures that would be wrong).
int gather_objects(const EvalOptions& o, const EvalParams& params, std::vector<EvalObject>& objects,
                   std::string& source);

// A progress bar on stderr; plain lines (every 10 %) when stderr is not a terminal.
class ProgressBar {
 public:
  ProgressBar() : tty_(isatty(STDERR_FILENO) != 0) {}
  ~ProgressBar() { finish_line(); }

  void operator()(const EvalProgress& p) {
    if (p.phase != phase_) {
      finish_line();
      phase_ = p.phase;
      last_decile_ = -1;
      start_ = std::chrono::steady_clock::now();
    }
    const double frac = p.total ? double(p.done) / double(p.total) : 1.0;
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (tty_) {
      const int width = 30, filled = static_cast<int>(frac * width);
      std::fprintf(stderr, "\r%-28s [%s%s] %zu/%zu %5.1fs", phase_.c_str(), std::string(filled, '#').c_str(),
                   std::string(width - filled, '.').c_str(), p.done, p.total, secs);
      open_ = true;
    } else if (int decile = static_cast<int>(frac * 10); decile > last_decile_) {
      last_decile_ = decile;
      std::fprintf(stderr, "%s: %zu/%zu (%.1fs)\n", phase_.c_str(), p.done, p.total, secs);
    }
    std::fflush(stderr);
  }

 private:
  void finish_line() {
    if (open_) std::fputc('\n', stderr);
    open_ = false;
  }
  bool tty_;
  bool open_ = false;
  std::string phase_;
  int last_decile_ = -1;
  std::chrono::steady_clock::time_point start_;
};


inline std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

// The size-blind ablation (every object 1 m tall, train and test) of `methods` (comma-separated): the
// same protocol without streams or the keypoint exploration, its accuracies added to `result`.
Status size_blind_ablation(EvalResult& result, const std::vector<EvalObject>& objects, const EvalParams& params,
                           const std::string& methods, ProgressBar& bar);

// The keypoint ablation (sec. 2.2, 3.2.1-3.2.2, 4): the keypoint methods re-run with one setting changed
// at a time (rho1 cap, claim radius, boundary band, support radius, vertices or samples, response,
// normalisation, PCA, decision, partial training), each row labelled with the keypoints its full views
// hold. No streams, matrix or exploration grid; the keypoint stages stay.
Status keypoint_ablation(EvalResult& result, const std::vector<EvalObject>& objects, const EvalParams& params,
                         ProgressBar& bar);

}  // namespace glimpse::lab

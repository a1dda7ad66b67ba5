// What the eval subcommand's pieces share: the progress bar, list parsing and the ablations run beside
// the main evaluation (lab_ablations.cpp).
#pragma once

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "glimpse/evaluation.h"

namespace glimpse::lab {

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

// run_evaluation's features, phases 3-4 (protocol.cpp runs them in order): every full view's
// features and keypoint cut margin, the stage cuts of tested views and the training prefixes of learnt
// ones (each computed once, in parallel over clouds), and the stage statistics over the tested views.
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <map>
#include <set>

#include "glimpse/lab/evaluation.h"
#include "glimpse/geometry/neighbourhoods.h"
#include "glimpse/geometry/surface_fit.h"
#include "glimpse/views/exploration.h"
#include "protocol.h"
#include "glimpse/threads.h"

namespace glimpse {

using namespace eval_internal;

void eval_internal::compute_slot(Protocol& P, FeatureSlot& slot, const Cloud& cloud) {
  const auto c0 = Clock::now();
  auto f = cloud_features(cloud, P.features, P.base, 1);
  slot.seconds = seconds_since(c0);
  slot.ok = f.ok();
  if (f.ok()) slot.features = std::move(*f);
  else slot.error = f.error().message;
}

// ---- 3. full-view features (and the keypoint cut margin) ----
void eval_internal::full_view_features(Protocol& P) {
  const auto t0 = Clock::now();
  const bool keypoint_stages = std::any_of(P.stages.begin(), P.stages.end(),
                                           [](const Stage& s) { return s.kind == StageKind::kKeypoints; });
  P.slots.assign(P.views.size(), {});
  P.margin.assign(P.views.size(), 0.f);
  parallel_for(P.views.size(), P.threads, "features: full views", P.progress, [&](size_t v) {
    P.slots[v].view = v;
    P.slots[v].count = P.views[v].cloud.points.size();
    if (!P.tested(v) && P.tilted(v)) return;  // only its tilted copy is learnt
    compute_slot(P, P.slots[v], P.views[v].cloud);
    if (keypoint_stages && P.tested(v) && P.views[v].cloud.points.size() > 1) {
      SurfaceParams sp = P.tp.features.surface;
      sp.threads = 1;
      const Points& pts = P.views[v].cloud.points;
      P.margin[v] = P.params.cut_margin_supports * support_radius(*first_guess_index(pts), sp);
    }
  });
  double cpu = 0;
  for (const FeatureSlot& s : P.slots) cpu += s.seconds;
  P.r.timings.push_back({"features: full views", seconds_since(t0),
                         std::to_string(P.slots.size()) + " clouds, " +
                             std::to_string(int(1000 * cpu / double(std::max<size_t>(1, P.slots.size())))) + " ms CPU each"});
}

// ---- 4. prefixes: the stage cuts of tested views and the training prefixes of learnt ones, each once ----
void eval_internal::prefix_features(Protocol& P) {
  const auto t0 = Clock::now();
  const size_t n_views = P.views.size();
  std::vector<std::map<size_t, int>> slot_of(n_views);
  P.stage_slot.assign(n_views, std::vector<int>(P.stages.size(), -1));
  P.train_slots.assign(n_views, {});
  P.seen_slots.assign(n_views, {});
  std::vector<std::map<size_t, int>> learnt_slot_of(n_views);
  auto slot_for = [&](size_t v, size_t count, bool learnt) -> int {
    if (count == 0) return -1;
    learnt = learnt && P.tilted(v);
    if (!learnt && count >= P.views[v].cloud.points.size()) return static_cast<int>(v);
    auto [it, fresh] = (learnt ? learnt_slot_of : slot_of)[v].emplace(count, static_cast<int>(P.slots.size()));
    if (fresh) {
      P.slots.emplace_back();
      P.slots.back().view = v;
      P.slots.back().count = count;
      P.slots.back().learnt = learnt;
    }
    return it->second;
  };
  for (size_t v = 0; v < n_views; ++v) {
    const Points& pts = P.views[v].cloud.points;
    if (P.tested(v)) {
      std::vector<float> heights;
      for (const Vec3& k : P.slots[v].features.positions) heights.push_back(k.z());
      for (size_t s = 0; s < P.stages.size(); ++s) {
        size_t count = pts.size();
        if (P.stages[s].kind == StageKind::kKeypoints)
          count = keypoint_prefix(pts, heights, static_cast<size_t>(P.stages[s].value), P.margin[v]);
        else if (P.stages[s].kind == StageKind::kFraction)
          count = fraction_prefix(pts.size(), P.full_points(v), P.stages[s].value);
        P.stage_slot[v][s] = slot_for(v, count, false);
      }
    }
    if (P.learnt(v)) {
      const size_t n = P.learnt_cloud(v).points.size();
      // A tilted view is learnt tilted; its held-out calibration decides it as seen (what a test cloud is).
      auto learn = [&](size_t count) {
        const int id = slot_for(v, count, true);
        if (id < 0) return;
        P.train_slots[v].push_back(id);
        P.seen_slots[v].push_back(P.tilted(v) && P.tp.calibration_folds >= 2 ? slot_for(v, count, false) : id);
      };
      learn(n);
      for (double f : P.tp.augmented_prefixes || !P.augmented(v) ? P.tp.partial_prefixes : std::vector<double>{}) {
        const size_t count = static_cast<size_t>(std::round(f * double(n)));
        if (count < n) learn(count);
      }
    }
  }
  const size_t first = n_views;
  parallel_for(P.slots.size() - first, P.threads, "features: prefixes", P.progress, [&](size_t j) {
    FeatureSlot& slot = P.slots[first + j];
    compute_slot(P, slot, reveal_top_down(slot.learnt ? P.learnt_cloud(slot.view) : P.views[slot.view].cloud, slot.count));
  });
  double cpu = 0;
  for (size_t i = first; i < P.slots.size(); ++i) cpu += P.slots[i].seconds;
  const size_t n = P.slots.size() - first;
  P.r.timings.push_back({"features: prefixes", seconds_since(t0),
                         std::to_string(n) + " distinct prefixes, " +
                             std::to_string(int(1000 * cpu / double(std::max<size_t>(1, n)))) + " ms CPU each"});
}

// ---- stage statistics (over the tested views) ----
void eval_internal::stage_statistics(Protocol& P) {
  EvalResult& r = P.r;
  const size_t n_cat = r.categories.size();
  for (size_t s = 0; s < P.stages.size(); ++s) {
    StageStats st;
    st.stage = stage_name(P.stages[s]);
    st.keypoints.assign(n_cat, 0), st.visible_percent.assign(n_cat, 0), st.failed.assign(n_cat, 0);
    std::vector<size_t> n(n_cat, 0);
    std::set<int> counted;
    size_t total_ok = 0;
    for (size_t v = 0; v < P.views.size(); ++v) {
      if (!P.tested(v) || P.unknown(v)) continue;
      const int c = r.object_truth[static_cast<size_t>(P.views[v].object)];
      const int id = P.stage_slot[v][s];
      if (id < 0 || !P.slots[id].ok) {
        ++st.failed[c];
        continue;
      }
      const FeatureSlot& slot = P.slots[id];
      const double visible = 100.0 * double(slot.count) / double(P.full_points(v));
      st.keypoints[c] += double(slot.features.positions.size());
      st.visible_percent[c] += visible;
      st.mean_keypoints += double(slot.features.positions.size());
      st.mean_visible_percent += visible;
      ++n[c], ++total_ok;
      if (counted.insert(id).second) st.feature_seconds += slot.seconds;
      if (P.stages[s].kind == StageKind::kKeypoints && P.slots[v].features.positions.size() >= P.stages[s].value) {
        const size_t k = slot.features.positions.size();
        st.cut_min_keypoints = st.cut_views ? std::min(st.cut_min_keypoints, k) : k;
        st.cut_max_keypoints = std::max(st.cut_max_keypoints, k);
        st.cut_mean_keypoints += double(k);
        st.cut_visible_percent += visible;
        ++st.cut_views;
      }
    }
    if (st.cut_views) st.cut_mean_keypoints /= double(st.cut_views), st.cut_visible_percent /= double(st.cut_views);
    for (size_t c = 0; c < n_cat; ++c)
      if (n[c]) st.keypoints[c] /= double(n[c]), st.visible_percent[c] /= double(n[c]);
    if (total_ok) st.mean_keypoints /= double(total_ok), st.mean_visible_percent /= double(total_ok);
    r.stage_stats.push_back(std::move(st));
  }
}

}  // namespace glimpse

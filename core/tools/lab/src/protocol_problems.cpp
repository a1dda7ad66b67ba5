// Phase 8 of run_evaluation: what looks wrong in a run (a method near chance, features that failed on
// some clouds, views without keypoints), as notes in the report.
#include <cctype>
#include <map>
#include <set>
#include <string>

#include "protocol.h"

namespace glimpse::eval_internal {

void flag_problems(Protocol& P) {
  EvalResult& r = P.r;
  size_t tested_views = 0;
  for (size_t v = 0; v < P.views.size(); ++v) tested_views += P.tested(v);
  const double chance = 100.0 / double(r.categories.size());
  for (MethodId m : P.params.methods) {
    const Tally t = accuracy(r.decisions, "full", m);
    if (t.total && t.percent() < chance + 10)
      r.notes.push_back(std::string(method_name(m)) + " is near chance on full views (" +
                        std::to_string(int(std::lround(t.percent()))) + " %, chance " +
                        std::to_string(int(std::lround(chance))) + " %).");
  }
  for (size_t s = 0; s < P.params.stages.size(); ++s) {
    const Stage& stage = P.params.stages[s];
    const StageStats& st = r.stage_stats[s];
    size_t failed = 0;
    for (size_t f : st.failed) failed += f;
    if (failed)
      r.notes.push_back("stage " + st.stage + ": features failed on " + std::to_string(failed) + " of " +
                        std::to_string(tested_views) + " views (counted as wrong decisions).");
    if (stage.kind != StageKind::kKeypoints) continue;
    size_t short_views = 0;
    for (size_t v = 0; v < P.views.size(); ++v) short_views += P.tested(v) && P.slots[v].features.positions.size() < stage.value;
    if (short_views)
      r.notes.push_back("stage " + st.stage + ": " + std::to_string(short_views) + " of " + std::to_string(tested_views) +
                        " views have fewer than " + stage_name(stage).substr(0, stage_name(stage).size() - 2) +
                        " keypoints on the full view, so the stage is the full view for them.");
  }
  // Feature errors grouped by their message with the numbers blanked out; the first one shown in full.
  struct ErrorGroup {
    size_t clouds = 0;
    std::string example;
    std::set<std::string> objects;
    size_t sensor_clouds = 0;  // of them, simulated sensors' training views (and their prefixes)
  };
  std::map<std::string, ErrorGroup> errors;
  for (const FeatureSlot& slot : P.slots) {
    if (slot.ok || slot.error.empty()) continue;  // computed fine, or never needed
    std::string key;
    for (char c : slot.error) {
      const bool digit = std::isdigit(static_cast<unsigned char>(c));
      if (!digit) key += c;
      else if (key.empty() || key.back() != '#') key += '#';
    }
    ErrorGroup& g = errors[key];
    const std::string& object = r.object_ids[static_cast<size_t>(P.views[slot.view].object)];
    if (g.clouds++ == 0)
      g.example = object + " view " + std::to_string(P.views[slot.view].view) + ", " + std::to_string(slot.count) +
                  " points: " + slot.error;
    g.objects.insert(object);
    g.sensor_clouds += P.views[slot.view].train_condition >= 0;
  }
  constexpr size_t kListed = 12;  // objects named; the rest counted
  for (const auto& [key, g] : errors) {
    std::string list;
    size_t listed = 0;
    for (const std::string& o : g.objects)
      if (listed++ < kListed) list += (list.empty() ? "" : ", ") + o;
    if (g.objects.size() > kListed) list += " and " + std::to_string(g.objects.size() - kListed) + " more";
    const std::string sensors = g.sensor_clouds ? ", " + std::to_string(g.sensor_clouds) +
                                                      " of them simulated sensors' training views (a far LiDAR leaves few points)"
                                                : "";
    r.notes.push_back("features failed on " + std::to_string(g.clouds) + " clouds (views and prefixes)" + sensors + " of " +
                      std::to_string(g.objects.size()) + " objects (" + list + "), e.g. " + g.example);
  }
  if (contains(P.params.methods, MethodId::kBoK) || contains(P.params.methods, MethodId::kBoG) ||
      contains(P.params.methods, MethodId::kKGH)) {
    size_t no_keypoints = 0;
    for (size_t v = 0; v < P.views.size(); ++v)
      no_keypoints += P.tested(v) && P.slots[v].ok && P.slots[v].features.positions.empty();
    if (no_keypoints)
      r.notes.push_back(std::to_string(no_keypoints) + " full views have no keypoint at all (BoK/BoG/KGH see nothing).");
  }
}

}  // namespace glimpse::eval_internal

// What the client prints of training and of stored models: progress lines and bars, the summary of a
// trained model, the models table, one model's details and its JSON.
#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cmath>

#include "client/render.h"
#include "proto/wire/methods.h"

namespace glimpse::client {

namespace {
std::string Methods(const v1::ModelInfo& m) {
  std::vector<std::string> names;
  for (int method : m.methods()) names.push_back(wire::MethodName(static_cast<v1::Method>(method)));
  return Joined(names, ",");
}
}  // namespace

// ---- train ----

namespace {
std::string StageText(const v1::TrainProgress& p) {
  std::string out = p.stage().empty() ? "starting" : p.stage();
  if (p.stage() == "receiving") return out + " " + std::to_string(p.clouds_received()) + " clouds";
  if (p.stage_total() > 0) {
    out += ' ';
    out += std::to_string(p.stage_done());
    out += '/';
    out += std::to_string(p.stage_total());
  }
  return out;
}

// ", about N s left" (minutes from 2 on) when the server estimates it, else "".
std::string TimeLeft(const v1::TrainProgress& p) {
  const double s = p.seconds_left();
  if (!(s > 0) || !std::isfinite(s)) return "";
  if (s < 120) return ", about " + std::to_string(std::max(1, static_cast<int>(std::lround(s)))) + " s left";
  return ", about " + std::to_string(static_cast<long>(std::lround(s / 60))) + " min left";
}
}  // namespace

std::string ProgressBar(const v1::TrainProgress& p, int bar_width) {
  std::string pct = Fixed(std::clamp(p.percent(), 0.0, 100.0), 0) + "%";
  if (pct.size() < 4) pct.insert(0, 4 - pct.size(), ' ');
  std::string out = "[";
  out += Bar(p.percent() / 100.0, bar_width);
  return out + "] " + pct + "  " + StageText(p) + TimeLeft(p);
}

std::string ProgressLine(const v1::TrainProgress& p) {
  return "train: " + Fixed(p.percent(), 0) + "% " + StageText(p) + " (clouds " + std::to_string(p.clouds_received()) +
         ")" + TimeLeft(p);
}

namespace {
// "N keypoints, " when the model learnt keypoints (BoK, BoG or KGH among its methods, or any found).
std::string KeypointsLearnt(const v1::ModelInfo& m) {
  bool keypoint_method = false;
  for (int method : m.methods()) {
    const auto id = wire::MethodFromProto(static_cast<v1::Method>(method));
    keypoint_method = keypoint_method || (id.ok() && *id && uses_keypoints(**id));
  }
  if (!keypoint_method && m.stats().keypoints() == 0) return "";
  return std::to_string(m.stats().keypoints()) + " keypoints, ";
}
}  // namespace

std::string TrainSummary(const v1::ModelInfo& m) {
  return "trained " + m.name() + ":" + std::to_string(m.version()) + (m.is_default() ? " (default)" : "") + ": " +
         std::to_string(m.categories_size()) + " categories, " + std::to_string(m.stats().clouds()) + " clouds, " +
         KeypointsLearnt(m) + Fixed(m.stats().seconds(), 1) + " s, " + FormatBytes(m.size_bytes()) +
         (m.grown_from().empty() ? "" : ", grown from " + m.grown_from());
}

// ---- models ----

std::string ModelsTable(const v1::ListModelsResponse& list) {
  if (list.models().empty()) return "no models\n";
  std::vector<std::vector<std::string>> table = {
      {"NAME", "VERSION", "DEFAULT", "CREATED", "METHODS", "CATEGORIES", "CLOUDS", "SIZE"}};
  for (const v1::ModelInfo& m : list.models())
    table.push_back({m.name(), std::to_string(m.version()), m.is_default() ? "*" : "", FormatTimestamp(m.created()),
                     Methods(m), std::to_string(m.categories_size()), std::to_string(m.stats().clouds()),
                     FormatBytes(m.size_bytes())});
  return Table(table);
}

std::string ModelDetails(const v1::ModelInfo& m) {
  std::vector<std::string> categories;
  for (const v1::CategoryCount& c : m.stats().categories())
    categories.push_back(c.category() + " (" + std::to_string(c.clouds()) + ")");
  if (categories.empty()) categories.assign(m.categories().begin(), m.categories().end());
  std::vector<std::vector<std::string>> rows = {
      {"name:", m.name()},
      {"version:", std::to_string(m.version()) + (m.is_default() ? " (default)" : "")},
      {"id:", std::to_string(m.id())},
      {"created:", FormatTimestamp(m.created())},
      {"description:", m.description().empty() ? "-" : m.description()},
      {"methods:", Methods(m) + " (default " + wire::MethodName(m.default_method()) + ")"},
      {"categories:", Joined(categories, ", ")},
      {"trained on:", std::to_string(m.stats().clouds()) + " clouds of " + std::to_string(m.stats().objects()) +
                          " objects, " + KeypointsLearnt(m) + Fixed(m.stats().seconds(), 1) + " s"},
      {"size:", FormatBytes(m.size_bytes())},
      {"sha256:", m.sha256().empty() ? "-" : m.sha256()},
      {"grown from:", m.grown_from().empty() ? "-" : m.grown_from()},
      {"can grow:", m.training_set_bytes() > 0 ? "yes (training set kept, " + FormatBytes(m.training_set_bytes()) + ")"
                                               : "no (no training set kept: train --base needs one)"},
  };
  return Table(rows);
}

std::string ModelJson(const v1::ModelInfo& m) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  std::string out;
  if (!google::protobuf::util::MessageToJsonString(m, &out, options).ok()) return "{}";
  return out;
}

}  // namespace glimpse::client

// Formatting shared by the evaluation report's writers (report*.cpp: the markdown sections;
// report_writers.cpp: CSV, SVG, the terminal summary and the report folder; robustness.cpp).
#pragma once

#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/lab/evaluation.h"

namespace glimpse::eval_internal {

inline std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// "12" / "12.5" style percent, "–" for NaN.
inline std::string pct(double v, int decimals = 0) {
  if (std::isnan(v)) return "–";
  return fmt(decimals ? "%.1f" : "%.0f", v);
}

inline std::string xml_escape(std::string_view s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

inline std::vector<std::string> main_stage_names(const EvalResult& r) {
  std::vector<std::string> out;
  for (const Stage& s : r.params.stages) out.push_back(stage_name(s));
  return out;
}

inline std::string method_label(MethodId m) {
  switch (m) {
    case MethodId::kBoK: return "BoK";
    case MethodId::kBoG: return "BoG";
    case MethodId::kKGH: return "KGH";
    case MethodId::kVFH: return "VFH";
    case MethodId::kESF: return "ESF";
    case MethodId::kUSH: return "USH";
    case MethodId::kSize: return "Size only";
    case MethodId::kFusion: return "Fusion";
  }
  return "?";
}

// Tested views: the full-view decisions of one method.
inline size_t tested_views(const EvalResult& r) {
  size_t n = 0;
  if (r.params.methods.empty()) return n;
  for (const StageDecision& d : r.decisions) n += d.stage == "full" && d.method == r.params.methods.front();
  return n;
}

inline const StageStats* stats_of(const EvalResult& r, std::string_view stage) {
  for (const StageStats& s : r.stage_stats)
    if (s.stage == stage) return &s;
  return nullptr;
}

}  // namespace glimpse::eval_internal

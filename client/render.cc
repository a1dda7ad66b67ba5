#include "client/render.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>

#include "client/parse.h"
#include "proto/wire/methods.h"

namespace glimpse::client {
namespace {

// Display width: UTF-8 code points (continuation bytes 10xxxxxx do not count).
size_t Width(std::string_view s) {
  return static_cast<size_t>(std::count_if(s.begin(), s.end(), [](char c) { return (c & 0xC0) != 0x80; }));
}

std::string Pad(std::string s, size_t width) {
  const size_t w = Width(s);
  if (w < width) s.append(width - w, ' ');
  return s;
}


template <class Scores>
std::string JsonScores(const Scores& scores) {
  std::string out = "{";
  for (const v1::CategoryScore& s : scores) {
    if (out.size() > 1) out += ",";
    out += JsonString(s.category());
    out += ":";
    out += JsonNumber(s.score());
  }
  return out + "}";
}

// ,"probabilities":{category: p, ...} when the answer has calibrated probabilities, else nothing.
template <class Scores>
std::string JsonProbabilities(const Scores& scores) {
  std::string out;
  for (const v1::CategoryScore& s : scores) {
    if (!s.has_probability()) return {};
    out += (out.empty() ? "" : ",") + JsonString(s.category()) + ":" + JsonNumber(s.probability());
  }
  return out.empty() ? out : ",\"probabilities\":{" + out + "}";
}

// What a person is shown of a category: its calibrated probability, or its score when the model has none.
double Shown(const v1::CategoryScore& s) { return s.has_probability() ? s.probability() : s.score(); }

double WinnerScore(const v1::Decision& d) {
  if (d.winner_index() < 0 || d.winner_index() >= d.scores_size()) return 0.0;
  return Shown(d.scores(d.winner_index()));
}

std::string YesNo(bool b) { return b ? "yes" : "no"; }

// "chair" or, for "none of these", "unknown (closest: chair 0.310)": the winner stays the nearest known
// category, so a person sees what it was closest to.
template <class Answer>
std::string WinnerText(const Answer& a, double winner_score) {
  if (a.winner().empty()) return "-";
  return a.unknown() ? "unknown (closest: " + a.winner() + " " + Score(winner_score) + ")" : a.winner();
}

double WinnerScore(const v1::ClassifyResponse& r) {
  if (r.winner_index() < 0 || r.winner_index() >= r.scores_size()) return 0.0;
  return Shown(r.scores(r.winner_index()));
}

// ["a","b"]
template <class Strings>
std::string JsonStrings(const Strings& items) {
  std::string out = "[";
  for (const std::string& s : items) out += (out.size() > 1 ? "," : "") + JsonString(s);
  return out + "]";
}

// ,"unknown":..,"novelty":..,"unknown_reason":..,"frame_cut":[..] (novelty null when the method has none)
template <class Answer>
std::string UnknownJson(const Answer& a) {
  return std::string(",\"unknown\":") + (a.unknown() ? "true" : "false") +
         ",\"novelty\":" + (a.has_novelty() ? JsonNumber(a.novelty()) : std::string("null")) +
         ",\"unknown_reason\":" + JsonString(a.unknown_reason()) + ",\"frame_cut\":" + JsonStrings(a.frame_cut());
}

// " target at 0.12,1.30,0.20 (4 objects)" or " target not found (why)" in a tracking stream; else empty.
std::string TrackedText(const v1::Decision& d) {
  if (!d.has_tracked()) return "";
  const v1::TrackedObject& t = d.tracked();
  if (!t.found()) return " target not found (" + t.not_found() + ")";
  const v1::Vec3& c = t.object().centroid();
  return " target at " + Fixed(c.x(), 2) + "," + Fixed(c.y(), 2) + "," + Fixed(c.z(), 2) + " (" +
         std::to_string(t.objects()) + (t.objects() == 1 ? " object)" : " objects)");
}

// ,"tracked":{"found":..,"objects":..,"centroid":[..],"box_min":[..],"box_max":[..],"not_found":..} in a tracking stream.
std::string TrackedJson(const v1::Decision& d) {
  if (!d.has_tracked()) return "";
  const v1::TrackedObject& t = d.tracked();
  auto vec = [](const v1::Vec3& v) {
    return "[" + JsonNumber(v.x()) + "," + JsonNumber(v.y()) + "," + JsonNumber(v.z()) + "]";
  };
  std::string out = std::string(",\"tracked\":{\"found\":") + (t.found() ? "true" : "false") +
                    ",\"objects\":" + std::to_string(t.objects());
  if (t.found())
    out += ",\"centroid\":" + vec(t.object().centroid()) + ",\"box_min\":" + vec(t.object().box_min()) +
           ",\"box_max\":" + vec(t.object().box_max()) + ",\"points\":" + std::to_string(t.object().points());
  return out + ",\"not_found\":" + JsonString(t.not_found()) + "}";
}

}  // namespace

std::string Fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "nan";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string JsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string Joined(const std::vector<std::string>& items, std::string_view separator) {
  std::string out;
  for (const std::string& s : items) out += (out.empty() ? "" : std::string(separator)) + s;
  return out;
}

std::string Bar(double fraction, int width) {
  static const char* const kEighths[] = {"", "▏", "▎", "▍", "▌", "▋", "▊", "▉"};
  if (width <= 0) return "";
  if (!std::isfinite(fraction)) fraction = 0.0;
  const int eighths = static_cast<int>(std::lround(std::clamp(fraction, 0.0, 1.0) * width * 8));
  const int full = eighths / 8, part = eighths % 8;
  std::string out;
  for (int i = 0; i < full; ++i) out += "█";
  out += kEighths[part];
  out.append(static_cast<size_t>(width - full - (part ? 1 : 0)), ' ');
  return out;
}

std::string Score(double score) { return Fixed(score, 3); }

std::string JsonString(std::string_view text) {
  std::string out = "\"";
  for (unsigned char c : text) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

std::string FormatTimestamp(const google::protobuf::Timestamp& t) {
  if (t.seconds() == 0 && t.nanos() == 0) return "-";
  const std::time_t s = static_cast<std::time_t>(t.seconds());
  std::tm tm{};
  gmtime_r(&s, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M:%SZ", &tm);
  return buf;
}

std::string FormatBytes(uint64_t bytes) {
  if (bytes < 1024) return std::to_string(bytes) + " B";
  const char* units[] = {"KiB", "MiB", "GiB", "TiB"};
  double v = static_cast<double>(bytes);
  int u = -1;
  while (v >= 1024.0 && u < 3) {
    v /= 1024.0;
    ++u;
  }
  return Fixed(v, 1) + " " + units[u];
}

std::string Table(const std::vector<std::vector<std::string>>& rows) {
  std::vector<size_t> widths;
  for (const auto& row : rows) {
    widths.resize(std::max(widths.size(), row.size()), 0);
    for (size_t c = 0; c < row.size(); ++c) widths[c] = std::max(widths[c], Width(row[c]));
  }
  std::string out;
  for (const auto& row : rows) {
    std::string line;
    for (size_t c = 0; c < row.size(); ++c) line += c + 1 < row.size() ? Pad(row[c], widths[c]) + "  " : row[c];
    out += line + "\n";
  }
  return out;
}

// ---- classify ----

std::string ClassifyTable(const std::vector<ClassifyRow>& rows) {
  std::vector<std::string> categories;  // union, in first-seen order (one model: its order)
  for (const ClassifyRow& r : rows)
    for (const v1::CategoryScore& s : r.response.scores())
      if (std::find(categories.begin(), categories.end(), s.category()) == categories.end())
        categories.push_back(s.category());
  std::vector<std::vector<std::string>> table;
  std::vector<std::string> header = {"FILE", "WINNER"};
  header.insert(header.end(), categories.begin(), categories.end());
  const bool novelty = std::any_of(rows.begin(), rows.end(), [](const ClassifyRow& r) { return r.response.has_novelty(); });
  if (novelty) header.push_back("NOVELTY");
  // Where the camera's frame cuts the object (clouds sent with their frame).
  const bool cut = std::any_of(rows.begin(), rows.end(), [](const ClassifyRow& r) { return r.response.frame_cut_size() > 0; });
  if (cut) header.push_back("CUT BY FRAME");
  header.insert(header.end(), {"POINTS", "KEYPOINTS", "MS"});
  table.push_back(header);
  for (const ClassifyRow& r : rows) {
    std::vector<std::string> line = {r.file, WinnerText(r.response, WinnerScore(r.response))};
    for (const std::string& c : categories) {
      std::string cell = "-";
      for (const v1::CategoryScore& s : r.response.scores())
        if (s.category() == c) cell = Score(Shown(s));
      line.push_back(cell);
    }
    if (novelty) line.push_back(r.response.has_novelty() ? Fixed(r.response.novelty(), 2) : "-");
    if (cut) {
      const std::vector<std::string> edges(r.response.frame_cut().begin(), r.response.frame_cut().end());
      line.push_back(edges.empty() ? "-" : Joined(edges, ","));
    }
    line.push_back(std::to_string(r.response.points()));
    line.push_back(std::to_string(r.response.keypoints()));
    line.push_back(Fixed(r.response.timings().total_ms(), 1));
    table.push_back(std::move(line));
  }
  return Table(table);
}

std::string ClassifyJson(const ClassifyRow& row) {
  return "{\"file\":" + JsonString(row.file) + "," + ClassifyJsonFields(row.response) + "}";
}

std::string ClassifyJsonFields(const v1::ClassifyResponse& r) {
  return "\"model\":" + JsonString(r.model().name()) +
         ",\"version\":" + std::to_string(r.model().version()) + ",\"method\":" + JsonString(wire::MethodName(r.method())) +
         ",\"winner\":" + JsonString(r.winner()) + ",\"scores\":" + JsonScores(r.scores()) + JsonProbabilities(r.scores()) +
         ",\"points\":" + std::to_string(r.points()) + ",\"keypoints\":" + std::to_string(r.keypoints()) +
         ",\"total_ms\":" + JsonNumber(r.timings().total_ms()) + ",\"warning\":" + JsonString(r.warning()) +
         UnknownJson(r);
}

std::string WinnerCell(const v1::ClassifyResponse& r) { return WinnerText(r, WinnerScore(r)); }

double WinnerShown(const v1::ClassifyResponse& r) { return WinnerScore(r); }

std::string ClassifyErrorJson(std::string_view file, std::string_view code, std::string_view message) {
  return "{\"file\":" + JsonString(file) + ",\"error\":{\"code\":" + JsonString(code) +
         ",\"message\":" + JsonString(message) + "}}";
}

// ---- stream ----

namespace {
// "keypoints N " unless the method uses none (whole-cloud descriptors only) and found none.
std::string KeypointsField(const v1::Decision& d, std::string_view gap) {
  const auto method = wire::MethodFromProto(d.method());
  const bool global_only = method.ok() && *method && !uses_keypoints(**method);
  if (global_only && d.keypoints() == 0) return "";
  return "keypoints " + std::to_string(d.keypoints()) + std::string(gap);
}
}  // namespace

std::string DecisionLine(const v1::Decision& d, size_t chunks_total) {
  std::string winner = d.winner().empty() ? "-"
                       : d.unknown()       ? WinnerText(d, WinnerScore(d))
                                           : d.winner() + " " + Score(WinnerScore(d));
  const std::string which =
      d.final() ? "final" : "chunk " + std::to_string(d.chunk_index() + 1) + "/" + std::to_string(chunks_total);
  return which + " points " +
         std::to_string(d.points()) + " " + KeypointsField(d, " ") + "winner " + winner +
         " changes " + std::to_string(d.category_changes()) + " settled " + YesNo(d.settled()) + " confidence " +
         Fixed(d.confidence(), 2) + (d.has_novelty() ? " novelty " + Fixed(d.novelty(), 2) : "") + TrackedText(d);
}

std::string DecisionPanel(const v1::Decision& d, size_t chunks_total, std::string_view previous_winner,
                          int bar_width) {
  const std::string which = d.final() ? "final (the whole scan, as Classify)"
                                      : "chunk " + std::to_string(d.chunk_index() + 1) + "/" + std::to_string(chunks_total);
  std::string out = "model " + FormatModelRef(d.model()) + " (" + wire::MethodName(d.method()) + ")   " + which + "   points " +
                    std::to_string(d.points()) + "   " + KeypointsField(d, "   ") +
                    Fixed(d.latency_ms(), 1) + " ms\n";
  if (d.winner().empty()) {
    out += "winner -   (not enough points yet)\n";
  } else {
    out += "winner " + (d.unknown() ? WinnerText(d, WinnerScore(d)) : d.winner() + " " + Score(WinnerScore(d)));
    if (!previous_winner.empty() && previous_winner != d.winner())
      out += "   (was " + std::string(previous_winner) + ")";
    out += "   changes " + std::to_string(d.category_changes()) + "   held " + std::to_string(d.winner_held_chunks()) +
           "   settled " + YesNo(d.settled()) + "   confidence " + Fixed(d.confidence(), 2) +
           (d.has_novelty() ? "   novelty " + Fixed(d.novelty(), 2) : "") + "\n";
    if (d.unknown() && !d.unknown_reason().empty()) out += "unknown: " + d.unknown_reason() + "\n";
    if (d.frame_cut_size() > 0) {
      const std::vector<std::string> edges(d.frame_cut().begin(), d.frame_cut().end());
      out += "the camera's frame cuts the scan at the " + Joined(edges, ", ") + ": the answer is of the part it shows\n";
    }
  }
  if (d.has_tracked()) out += TrackedText(d).substr(1) + "\n";
  size_t name_width = 0;
  for (const v1::CategoryScore& s : d.scores()) name_width = std::max(name_width, Width(s.category()));
  for (int i = 0; i < d.scores_size(); ++i) {
    const v1::CategoryScore& s = d.scores(i);
    out += (i == d.winner_index() ? "> " : "  ") + Pad(s.category(), name_width) + "  " + Bar(Shown(s), bar_width) +
           "  " + Score(Shown(s)) + "\n";
  }
  return out;
}

std::string DecisionJson(const v1::Decision& d, size_t chunks_total) {
  return "{\"chunk\":" + std::to_string(d.chunk_index() + 1) + ",\"chunks\":" + std::to_string(chunks_total) +
         ",\"points\":" + std::to_string(d.points()) + ",\"keypoints\":" + std::to_string(d.keypoints()) +
         ",\"winner\":" + JsonString(d.winner()) + ",\"scores\":" + JsonScores(d.scores()) + JsonProbabilities(d.scores()) +
         ",\"raw_scores\":" + JsonScores(d.raw_scores()) + ",\"final\":" + (d.final() ? "true" : "false") +
         ",\"changes\":" + std::to_string(d.category_changes()) + ",\"held\":" + std::to_string(d.winner_held_chunks()) +
         ",\"settled\":" + (d.settled() ? "true" : "false") + ",\"confidence\":" + JsonNumber(d.confidence()) +
         ",\"model\":" + JsonString(d.model().name()) + ",\"version\":" + std::to_string(d.model().version()) +
         ",\"method\":" + JsonString(wire::MethodName(d.method())) + ",\"latency_ms\":" + JsonNumber(d.latency_ms()) +
         UnknownJson(d) + TrackedJson(d) + "}";
}

int LineCount(std::string_view text) { return static_cast<int>(std::count(text.begin(), text.end(), '\n')); }

}  // namespace glimpse::client

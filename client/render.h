// Everything the client prints, as pure functions from messages to text: score tables, bars, the
// live scan panel, progress bars, model listings, and JSON lines for scripts. No I/O here.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "glimpse/v1/glimpse.pb.h"

namespace glimpse::client {

// ---- building blocks ----

// A horizontal bar `width` cells wide, filled `fraction` (clamped to [0, 1]) with Unicode blocks in
// eighths of a cell, padded with spaces.
std::string Bar(double fraction, int width);
// "0.820"; "nan" for non-finite.
std::string Score(double score);
// A JSON string literal (quotes, backslashes and control characters escaped).
std::string JsonString(std::string_view text);
// A JSON number with 6 significant digits; null for non-finite.
std::string JsonNumber(double v);
// "3.14" with `decimals` decimals; "nan" for non-finite.
std::string Fixed(double v, int decimals);
// The items with `separator` between them.
std::string Joined(const std::vector<std::string>& items, std::string_view separator);
// "2024-05-01 12:00:03Z" (UTC); "-" when unset.
std::string FormatTimestamp(const google::protobuf::Timestamp& t);
// "512 B", "1.2 KiB", "3.4 MiB".
std::string FormatBytes(uint64_t bytes);
// Columns separated by two spaces, each as wide as its widest cell; the first row is the header.
std::string Table(const std::vector<std::vector<std::string>>& rows);

// ---- classify ----

struct ClassifyRow {
  std::string file;
  v1::ClassifyResponse response;
};
// One row per file: FILE WINNER <category...> [NOVELTY] POINTS KEYPOINTS MS, categories in the model's
// order; WINNER "unknown (closest: chair 0.310)" for "none of these", NOVELTY when an answer has one.
std::string ClassifyTable(const std::vector<ClassifyRow>& rows);
// {"file":..,"model":..,"version":..,"method":..,"winner":..,"scores":{cat:score,..},"points":..,
//  "keypoints":..,"total_ms":..,"warning":..,"unknown":..,"novelty":..,"unknown_reason":..} (warning ""
//  when all is well; novelty null when the method has none)
std::string ClassifyJson(const ClassifyRow& row);
// ClassifyJson's fields after "file", without braces (for answers nested in other JSON).
std::string ClassifyJsonFields(const v1::ClassifyResponse& r);
// "chair", or "unknown (closest: chair 0.310)"; the winner's probability (or score).
std::string WinnerCell(const v1::ClassifyResponse& r);
double WinnerShown(const v1::ClassifyResponse& r);
// A file that got no answer, in the same shape a script can tell apart by "error":
// {"file":..,"error":{"code":"NOT_FOUND","message":..}}
std::string ClassifyErrorJson(std::string_view file, std::string_view code, std::string_view message);

// ---- stream ----

// "chunk 3/20 points 1234 keypoints 17 winner chair 0.820 changes 1 settled no confidence 0.41 novelty 0.93"
// (chunk is 1-based; winner "-" while undecided, "unknown (closest: chair 0.820)" for "none of these";
// novelty when the method has one).
std::string DecisionLine(const v1::Decision& d, size_t chunks_total);
// The live panel redrawn on a terminal: position, winner (and the previous one when it just changed),
// settled state, and one bar per category. Ends with a newline; LineCount() tells how many.
std::string DecisionPanel(const v1::Decision& d, size_t chunks_total, std::string_view previous_winner,
                          int bar_width = 30);
// {"chunk":3,"chunks":20,"points":..,"keypoints":..,"winner":..,"scores":{..},"changes":..,
//  "held":..,"settled":false,"confidence":..,"latency_ms":..,"unknown":..,"novelty":..,"unknown_reason":..}
std::string DecisionJson(const v1::Decision& d, size_t chunks_total);

// ---- train ----

// "[██████▍        ]  43%  features 12/30" (no newline; the caller redraws it with \r).
std::string ProgressBar(const v1::TrainProgress& p, int bar_width = 30);
// "train: 43% features 12/30 (clouds 30)"
std::string ProgressLine(const v1::TrainProgress& p);
// "trained zoo:2 (default): 5 categories, 60 clouds, 1234 keypoints, 12.3 s, 1.2 MiB"
std::string TrainSummary(const v1::ModelInfo& m);

// ---- models ----

// NAME VERSION DEFAULT CREATED METHODS CATEGORIES CLOUDS SIZE; "no models" when empty.
std::string ModelsTable(const v1::ListModelsResponse& list);
// "name: zoo\nversion: 2\n..." every field a person wants, one per line.
std::string ModelDetails(const v1::ModelInfo& m);
// The message as one line of JSON with the proto's field names.
std::string ModelJson(const v1::ModelInfo& m);

// Counts '\n' in text.
int LineCount(std::string_view text);

}  // namespace glimpse::client

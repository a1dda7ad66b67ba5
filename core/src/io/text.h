// Shared pieces of the file readers (io*.cpp only): a bounded whole-file read, a line cursor that
// knows its line number, number parsing that never throws, and error formatting "file:line: why".
#pragma once

#include <charconv>
#include <optional>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse::io_detail {

inline constexpr uint64_t kMaxFileBytes = 8ull << 30;  // refuse to slurp files above 8 GiB
inline constexpr uint64_t kMaxPoints = 100'000'000;    // vertices / points per file
inline constexpr uint64_t kMaxFaces = 200'000'000;     // triangles per file

Expected<std::string> read_file(const std::string& path);

inline Error text_error(const std::string& path, size_t line, const std::string& why) {
  return data_loss(path + ":" + std::to_string(line) + ": " + why);
}
inline Error byte_error(const std::string& path, size_t offset, const std::string& why) {
  return data_loss(path + ": byte offset " + std::to_string(offset) + ": " + why);
}

// Walks a text buffer line by line; '\r' before '\n' is dropped. `line_no` is 1-based.
class LineCursor {
 public:
  explicit LineCursor(std::string_view text, size_t start = 0) : text_(text), pos_(start) {}
  bool next(std::string_view& line);
  size_t line_no() const { return line_no_; }
  size_t offset() const { return pos_; }
  size_t remaining() const { return text_.size() - pos_; }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  size_t line_no_ = 0;
};

// Removes a '#' comment and surrounding blanks.
std::string_view strip_comment(std::string_view line, char mark = '#');
std::string_view trim(std::string_view s);
// Splits on blanks (and on commas when `commas`); empty tokens are dropped.
void split(std::string_view line, std::vector<std::string_view>& out, bool commas = false);

bool parse_double(std::string_view token, double& out);  // accepts a leading '+', nan, inf
bool parse_u64(std::string_view token, uint64_t& out);
bool parse_i64(std::string_view token, int64_t& out);
std::string lower(std::string_view s);

// The writers print floats with the shortest text that reads back to the same value.
void append_float(std::string& out, float v);

Status write_bytes(const std::string& path, const std::string& data);

// Fan-triangulates a polygon (already validated indices) into `faces`.
void add_fan(const std::vector<int>& polygon, std::vector<Eigen::Vector3i>& faces);

// The cloud readers keep a view stored by our writers as comments: "glimpse_sensor x y z" (Cloud.sensor)
// and "glimpse_frame ax ay az ux uy uz fov_h fov_v" (Cloud.frame). True when `comment` (after its
// comment marker) is one of them; it then sets that member of `view`.
bool parse_view_comment(std::string_view comment, Cloud& view);
// Those comments of `cloud`, each line starting with `marker` ("# ", "comment ").
void append_view_comments(std::string& out, const Cloud& cloud, std::string_view marker);

Expected<Mesh> read_off(const std::string& path, std::string_view text);
Expected<Mesh> read_obj(const std::string& path, std::string_view text);
Expected<Mesh> read_stl(const std::string& path, std::string_view data);  // binary or ASCII
// `view`: where a cloud's comments (parse_view_comment) go; nullptr for a mesh.
Expected<Mesh> read_ply(const std::string& path, std::string_view text, bool vertices_only, Cloud* view);
// `viewpoint`: when given, the VIEWPOINT's 7 numbers (translation, rotation w x y z; the default's when none).
Expected<Cloud> read_pcd(const std::string& path, std::string_view text, double* viewpoint = nullptr);

// A PCD field as its header declares it, and where it lies in a point's record (binary) or line (ascii).
struct PcdField {
  std::string name;
  uint64_t size = 4;
  char type = 'F';
  uint64_t count = 1;
  uint64_t offset = 0;  // bytes into a binary point record
  uint64_t column = 0;  // token index in an ascii point line
};
// LZF's densest code, a back reference of 3 bytes, repeats at most 264 bytes: no body expands more.
inline constexpr uint64_t kLzfMaxExpansion = 88;
// A DATA binary_compressed body from byte `start` of `text` (LZF, each field's values stored together),
// decompressed and unpacked by PCL's reader (pcd_compressed.cpp) into `points` records of `record_bytes`,
// as DATA binary stores them. `fields` hold no '_' padding fields (PCL's writer drops them). Errors
// (kDataLoss) name the path and the body's byte offset.
Expected<std::string> read_compressed_body(const std::string& path, std::string_view text, size_t start,
                                           const std::vector<PcdField>& fields, uint64_t points, uint64_t record_bytes);
Status write_ply(const std::string& path, const Cloud& cloud);
Status write_pcd(const std::string& path, const Cloud& cloud);

}  // namespace glimpse::io_detail

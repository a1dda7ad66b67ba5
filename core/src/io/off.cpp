// The two text mesh formats: OFF (Princeton shape benchmark, SHREC) and Wavefront OBJ.
#include <cstdint>
#include <string>
#include <vector>

#include "io/text.h"

namespace glimpse::io_detail {
namespace {

// Next line holding something other than blanks and '#' comments, as tokens.
bool next_tokens(LineCursor& lines, std::vector<std::string_view>& tok) {
  std::string_view line;
  while (lines.next(line)) {
    split(strip_comment(line), tok);
    if (!tok.empty()) return true;
  }
  return false;
}

// OFF, COFF, NOFF, STOFF, ... (3-D only); returns the prefix letters were all known.
bool is_off_header(std::string_view t) {
  if (t.size() < 3 || t.substr(t.size() - 3) != "OFF") return false;
  for (char c : t.substr(0, t.size() - 3))
    if (c != 'C' && c != 'N' && c != 'S' && c != 'T') return false;
  return true;
}

}  // namespace

Expected<Mesh> read_off(const std::string& path, std::string_view text) {
  LineCursor lines(text);
  std::vector<std::string_view> tok;
  if (!next_tokens(lines, tok) || !is_off_header(tok[0]))
    return text_error(path, lines.line_no(), "missing OFF header");
  std::vector<std::string_view> counts(tok.begin() + 1, tok.end());  // "OFF nv nf ne" on one line
  if (counts.empty()) {
    if (!next_tokens(lines, tok)) return text_error(path, lines.line_no(), "missing vertex/face counts");
    counts = tok;
  }
  uint64_t nv = 0, nf = 0;
  if (counts.size() < 2 || !parse_u64(counts[0], nv) || !parse_u64(counts[1], nf))
    return text_error(path, lines.line_no(), "expected 'vertices faces [edges]' counts");
  // A vertex line takes at least 6 bytes ("0 0 0\n"), a face line at least 8 ("3 0 1 2\n").
  if (nv > kMaxPoints || nf > kMaxFaces)
    return text_error(path, lines.line_no(), "counts above the limit of " + std::to_string(kMaxPoints) +
                                                 " vertices / " + std::to_string(kMaxFaces) + " faces");
  if (nv * 6 + nf * 8 > lines.remaining() + 1)  // the last line may lack its newline
    return text_error(path, lines.line_no(),
                      "counts (" + std::to_string(nv) + " vertices, " + std::to_string(nf) +
                          " faces) exceed what the file can hold");
  Mesh mesh;
  mesh.vertices.reserve(nv);
  mesh.faces.reserve(nf);
  for (uint64_t i = 0; i < nv; ++i) {
    if (!next_tokens(lines, tok))
      return text_error(path, lines.line_no(), "truncated: expected " + std::to_string(nv) +
                                                   " vertices, found " + std::to_string(i));
    double v[3];
    if (tok.size() < 3 || !parse_double(tok[0], v[0]) || !parse_double(tok[1], v[1]) ||
        !parse_double(tok[2], v[2]))
      return text_error(path, lines.line_no(), "expected a vertex 'x y z'");
    mesh.vertices.emplace_back(float(v[0]), float(v[1]), float(v[2]));
  }
  std::vector<int> polygon;
  for (uint64_t i = 0; i < nf; ++i) {
    if (!next_tokens(lines, tok))
      return text_error(path, lines.line_no(), "truncated: expected " + std::to_string(nf) +
                                                   " faces, found " + std::to_string(i));
    uint64_t n = 0;
    if (!parse_u64(tok[0], n) || n < 3 || n >= tok.size())  // not n + 1 > size: n + 1 wraps at 2^64 - 1
      return text_error(path, lines.line_no(), "expected a face 'n i1 ... in' with n >= 3");
    polygon.clear();
    for (uint64_t k = 0; k < n; ++k) {
      uint64_t idx = 0;
      if (!parse_u64(tok[1 + k], idx) || idx >= nv)
        return text_error(path, lines.line_no(), "bad vertex index '" + std::string(tok[1 + k]) + "'");
      polygon.push_back(static_cast<int>(idx));
    }
    if (mesh.faces.size() + n > kMaxFaces) return text_error(path, lines.line_no(), "too many faces");
    add_fan(polygon, mesh.faces);  // colour values after the indices are ignored
  }
  return mesh;  // anything after the face list is ignored
}

namespace {

// "7", "7/1", "7//3", "7/1/3", "-2/..." -> 0-based index, or -1 when malformed / out of range.
int64_t obj_index(std::string_view t, size_t vertex_count) {
  const size_t slash = t.find('/');
  int64_t i = 0;
  if (!parse_i64(t.substr(0, slash), i) || i == 0) return -1;
  const int64_t n = static_cast<int64_t>(vertex_count);
  const int64_t idx = i > 0 ? i - 1 : n + i;  // negative: relative to the vertices read so far
  return idx >= 0 && idx < n ? idx : -1;
}

}  // namespace

Expected<Mesh> read_obj(const std::string& path, std::string_view text) {
  LineCursor lines(text);
  std::string_view line;
  std::vector<std::string_view> tok;
  std::vector<int> polygon;
  Mesh mesh;
  while (lines.next(line)) {
    split(strip_comment(line), tok);
    if (tok.empty()) continue;
    if (tok[0] == "v") {
      double v[3];
      if (tok.size() < 4 || !parse_double(tok[1], v[0]) || !parse_double(tok[2], v[1]) ||
          !parse_double(tok[3], v[2]))
        return text_error(path, lines.line_no(), "expected 'v x y z'");
      if (mesh.vertices.size() >= kMaxPoints) return text_error(path, lines.line_no(), "too many vertices");
      mesh.vertices.emplace_back(float(v[0]), float(v[1]), float(v[2]));
    } else if (tok[0] == "f") {
      if (tok.size() < 4) return text_error(path, lines.line_no(), "a face needs at least 3 vertices");
      polygon.clear();
      for (size_t k = 1; k < tok.size(); ++k) {
        const int64_t idx = obj_index(tok[k], mesh.vertices.size());
        if (idx < 0)
          return text_error(path, lines.line_no(), "bad vertex index '" + std::string(tok[k]) + "'");
        polygon.push_back(static_cast<int>(idx));
      }
      if (mesh.faces.size() + polygon.size() > kMaxFaces)
        return text_error(path, lines.line_no(), "too many faces");
      add_fan(polygon, mesh.faces);
    }
    // vt, vn, g, o, s, l, p, usemtl, mtllib, ...: not geometry we use
  }
  if (mesh.vertices.empty()) return data_loss(path + ": no 'v' records (not an OBJ file?)");
  return mesh;
}

}  // namespace glimpse::io_detail

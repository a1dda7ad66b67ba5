// STL (stereolithography), the format CAD tools export: binary (80-byte header, a uint32 triangle
// count, 50 bytes per triangle) and ASCII ("solid ... facet normal ... outer loop vertex x y z ...").
// STL stores every triangle's corners on their own; corners with bit-identical coordinates are
// welded into one vertex so the mesh's vertices are the surface's points, each once.
#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <string>
#include <unordered_map>
#include <vector>

#include "io/text.h"

namespace glimpse::io_detail {
namespace {

constexpr size_t kHeaderBytes = 80;
constexpr size_t kTriangleBytes = 50;  // normal (3 float32), 3 corners (9 float32), attribute (uint16)

uint32_t read_u32_le(const char* p) {
  const auto* b = reinterpret_cast<const unsigned char*>(p);
  return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
}

float read_f32_le(const char* p) {
  const uint32_t bits = read_u32_le(p);
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

// Welds corners with bit-identical coordinates (+0 and -0 are one point).
class Welder {
 public:
  explicit Welder(Mesh& mesh) : mesh_(mesh) {}
  int add(const Vec3& v) {
    Key k{bits(v.x()), bits(v.y()), bits(v.z())};
    auto [it, fresh] = index_.emplace(k, static_cast<int>(mesh_.vertices.size()));
    if (fresh) mesh_.vertices.push_back(v);
    return it->second;
  }

 private:
  struct Key {
    uint32_t x, y, z;
    bool operator==(const Key&) const = default;
  };
  struct Hash {
    size_t operator()(const Key& k) const {
      uint64_t h = (uint64_t(k.x) * 0x9E3779B97F4A7C15ull) ^ (uint64_t(k.y) * 0xC2B2AE3D27D4EB4Full) ^
                   (uint64_t(k.z) * 0x165667B19E3779F9ull);
      return static_cast<size_t>(h ^ (h >> 29));
    }
  };
  static uint32_t bits(float f) {
    if (f == 0.f) f = 0.f;  // -0 -> +0
    uint32_t b;
    std::memcpy(&b, &f, sizeof b);
    return b;
  }
  Mesh& mesh_;
  std::unordered_map<Key, int, Hash> index_;
};

void add_triangle(Welder& weld, Mesh& mesh, const Vec3 (&corner)[3]) {
  const int a = weld.add(corner[0]), b = weld.add(corner[1]), c = weld.add(corner[2]);
  // A triangle whose corners weld together has no area: it holds no surface to sample.
  if (a != b && b != c && a != c) mesh.faces.emplace_back(a, b, c);
}

Expected<Mesh> read_binary_stl(const std::string& path, std::string_view data, uint64_t triangles) {
  if (triangles > kMaxFaces)
    return byte_error(path, kHeaderBytes, "triangle count " + std::to_string(triangles) + " above the limit of " +
                                              std::to_string(kMaxFaces));
  Mesh mesh;
  mesh.faces.reserve(triangles);
  Welder weld(mesh);
  for (uint64_t t = 0; t < triangles; ++t) {
    const size_t at = kHeaderBytes + 4 + t * kTriangleBytes + 12;  // skip the stored normal
    Vec3 corner[3];
    for (int c = 0; c < 3; ++c) {
      const char* p = data.data() + at + 12 * c;
      corner[c] = Vec3(read_f32_le(p), read_f32_le(p + 4), read_f32_le(p + 8));
      if (!corner[c].allFinite())
        return byte_error(path, at + 12 * c, "triangle " + std::to_string(t) + " has a non-finite corner");
    }
    add_triangle(weld, mesh, corner);
  }
  if (mesh.vertices.empty()) return data_loss(path + ": binary STL with no triangles");
  return mesh;
}

Expected<Mesh> read_ascii_stl(const std::string& path, std::string_view text) {
  LineCursor lines(text);
  std::string_view line;
  std::vector<std::string_view> tok;
  Mesh mesh;
  Welder weld(mesh);
  Vec3 corner[3];
  int corners = -1;  // -1: outside a facet's loop
  bool solid = false, ended = false;
  while (lines.next(line)) {
    split(trim(line), tok);
    if (tok.empty()) continue;
    const std::string word = lower(tok[0]);
    if (!solid) {
      if (word != "solid") return text_error(path, lines.line_no(), "expected 'solid' (not an STL file?)");
      solid = true;
    } else if (word == "facet" || word == "outer") {
      if (corners != -1) return text_error(path, lines.line_no(), "'" + word + "' inside a facet's loop");
      if (word == "outer") corners = 0;
    } else if (word == "vertex") {
      if (corners < 0) return text_error(path, lines.line_no(), "'vertex' outside an 'outer loop'");
      if (corners == 3) return text_error(path, lines.line_no(), "a facet with more than 3 vertices");
      double v[3];
      if (tok.size() != 4 || !parse_double(tok[1], v[0]) || !parse_double(tok[2], v[1]) ||
          !parse_double(tok[3], v[2]))
        return text_error(path, lines.line_no(), "expected 'vertex x y z'");
      corner[corners] = Vec3(float(v[0]), float(v[1]), float(v[2]));
      if (!corner[corners].allFinite()) return text_error(path, lines.line_no(), "non-finite vertex");
      ++corners;
    } else if (word == "endloop") {
      if (corners != 3) return text_error(path, lines.line_no(), "a facet needs exactly 3 vertices");
      if (mesh.faces.size() >= kMaxFaces) return text_error(path, lines.line_no(), "too many facets");
      add_triangle(weld, mesh, corner);
      corners = -1;
    } else if (word == "endfacet") {
      if (corners != -1) return text_error(path, lines.line_no(), "'endfacet' before 'endloop'");
    } else if (word == "endsolid") {
      if (corners != -1) return text_error(path, lines.line_no(), "'endsolid' inside a facet");
      ended = true;
      solid = false;  // another solid may follow (several bodies in one file)
    } else {
      return text_error(path, lines.line_no(), "unexpected '" + std::string(tok[0].substr(0, 40)) + "'");
    }
  }
  if (!solid && !ended) return data_loss(path + ": no 'solid' (not an STL file?)");
  if (solid && corners != -1) return text_error(path, lines.line_no(), "truncated inside a facet");
  if (mesh.vertices.empty()) return data_loss(path + ": STL with no facets");
  return mesh;
}

}  // namespace

Expected<Mesh> read_stl(const std::string& path, std::string_view data) {
  // Binary exporters often begin the header with "solid" too, so the size decides: a binary file is
  // exactly 84 + 50 n bytes for the n its header states.
  if (data.size() >= kHeaderBytes + 4) {
    const uint64_t n = read_u32_le(data.data() + kHeaderBytes);
    if (data.size() == kHeaderBytes + 4 + n * kTriangleBytes) return read_binary_stl(path, data, n);
  }
  // Text holds no control bytes but blanks; binary floats and counts nearly always do.
  const bool text = std::none_of(data.begin(), data.end(), [](char c) {
    const auto b = static_cast<unsigned char>(c);
    return b < 0x20 && b != '\n' && b != '\r' && b != '\t' && b != '\f' && b != '\v';
  });
  size_t start = 0;
  while (start < data.size() && std::isspace(static_cast<unsigned char>(data[start]))) ++start;
  if (text && (data.substr(start, 5) == "solid" || data.substr(start, 5) == "SOLID")) return read_ascii_stl(path, data);
  if (data.size() < kHeaderBytes + 4)
    return byte_error(path, data.size(), "truncated: a binary STL needs an 80-byte header and a triangle count");
  const uint64_t n = read_u32_le(data.data() + kHeaderBytes);
  return byte_error(path, kHeaderBytes, "binary STL header states " + std::to_string(n) + " triangles (" +
                                            std::to_string(kHeaderBytes + 4 + n * kTriangleBytes) +
                                            " bytes), the file has " + std::to_string(data.size()) + " bytes");
}

}  // namespace glimpse::io_detail

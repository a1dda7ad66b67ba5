// PLY (Stanford polygon format, Turk 1994): ascii, binary_little_endian and binary_big_endian bodies.
#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "io/text.h"

namespace glimpse::io_detail {
namespace {

enum class Type { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64, kBad };

Type parse_type(std::string_view t) {
  if (t == "char" || t == "int8") return Type::kInt8;
  if (t == "uchar" || t == "uint8") return Type::kUInt8;
  if (t == "short" || t == "int16") return Type::kInt16;
  if (t == "ushort" || t == "uint16") return Type::kUInt16;
  if (t == "int" || t == "int32") return Type::kInt32;
  if (t == "uint" || t == "uint32") return Type::kUInt32;
  if (t == "float" || t == "float32") return Type::kFloat32;
  if (t == "double" || t == "float64") return Type::kFloat64;
  return Type::kBad;
}

size_t type_size(Type t) {
  switch (t) {
    case Type::kInt8: case Type::kUInt8: return 1;
    case Type::kInt16: case Type::kUInt16: return 2;
    case Type::kInt32: case Type::kUInt32: case Type::kFloat32: return 4;
    case Type::kFloat64: return 8;
    case Type::kBad: break;
  }
  return 0;
}

struct Property {
  std::string name;
  Type type = Type::kBad;
  bool is_list = false;
  Type count_type = Type::kBad;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> props;
  size_t header_line = 0;
};

enum class Format { kAscii, kLittle, kBig };

// Reads the body value by value, in ascii (one element item per line) or binary (either endianness).
class Body {
 public:
  Body(const std::string& path, std::string_view text, size_t start, size_t start_line, Format f)
      : path_(path), text_(text), pos_(start), line_(start_line), format_(f) {}

  size_t remaining() const { return text_.size() - pos_; }
  // The fewest bytes one value can take: its size in binary, one character in ascii.
  size_t min_bytes(Type t) const { return format_ == Format::kAscii ? 1 : type_size(t); }

  // One value of type t as double; false and `error` set when the data runs out or is malformed.
  bool read(Type t, double& out, Error& error) {
    if (format_ == Format::kAscii) return read_token(out, error);
    const size_t n = type_size(t);
    if (remaining() < n) {
      error = byte_error(path_, pos_, "unexpected end of data");
      return false;
    }
    unsigned char b[8];
    std::memcpy(b, text_.data() + pos_, n);
    pos_ += n;
    const bool swap = (format_ == Format::kBig) != (std::endian::native == std::endian::big);
    if (swap) std::reverse(b, b + n);
    switch (t) {
      case Type::kInt8: out = static_cast<int8_t>(b[0]); break;
      case Type::kUInt8: out = b[0]; break;
      case Type::kInt16: { int16_t v; std::memcpy(&v, b, 2); out = v; break; }
      case Type::kUInt16: { uint16_t v; std::memcpy(&v, b, 2); out = v; break; }
      case Type::kInt32: { int32_t v; std::memcpy(&v, b, 4); out = v; break; }
      case Type::kUInt32: { uint32_t v; std::memcpy(&v, b, 4); out = v; break; }
      case Type::kFloat32: { float v; std::memcpy(&v, b, 4); out = v; break; }
      case Type::kFloat64: { double v; std::memcpy(&v, b, 8); out = v; break; }
      case Type::kBad: return false;
    }
    return true;
  }

  // Ascii: an item's values are one line (the format's rule): the first may follow blank lines, the
  // others stay on its line, and nothing may follow the last. Without it an extra column would shift
  // every later value silently. Binary: nothing to check.
  void begin_item(const std::string& element, size_t properties) {
    element_ = &element;
    properties_ = properties;
    in_item_ = false;
  }
  bool end_item(Error& error) {
    if (format_ != Format::kAscii) return true;
    while (pos_ < text_.size() && text_[pos_] != '\n' && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    if (pos_ < text_.size() && text_[pos_] != '\n') {
      error = text_error(path_, line_, "more values than element '" + *element_ + "' has properties (" +
                                           std::to_string(properties_) + "; one item per line)");
      return false;
    }
    return true;
  }

  Error where(const std::string& why) const {
    return format_ == Format::kAscii ? text_error(path_, line_, why) : byte_error(path_, pos_, why);
  }

 private:
  bool read_token(double& out, Error& error) {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) {
      if (text_[pos_] == '\n') {
        if (in_item_) {
          error = text_error(path_, line_, "fewer values than element '" + *element_ + "' has properties (" +
                                               std::to_string(properties_) + "; one item per line)");
          return false;
        }
        ++line_;
      }
      ++pos_;
    }
    in_item_ = true;
    const size_t b = pos_;
    while (pos_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    if (b == pos_) {
      error = text_error(path_, line_, "unexpected end of data");
      return false;
    }
    if (!parse_double(text_.substr(b, pos_ - b), out)) {
      error = text_error(path_, line_, "not a number: '" + std::string(text_.substr(b, pos_ - b)) + "'");
      return false;
    }
    return true;
  }

  const std::string& path_;
  std::string_view text_;
  size_t pos_;
  size_t line_;
  Format format_;
  const std::string* element_ = nullptr;
  size_t properties_ = 0;
  bool in_item_ = false;
};

bool is_index_list(const Property& p) {
  return p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index");
}

// What a PLY header declares.
struct PlyHeader {
  Format format = Format::kAscii;
  std::vector<Element> elements;
};

// A "property" line (its tokens `tok`, of line `ln`): a scalar or a list.
Expected<Property> read_property(const std::string& path, size_t ln, const std::vector<std::string_view>& tok) {
  Property p;
  if (tok.size() == 5 && tok[1] == "list") {
    p.is_list = true;
    p.count_type = parse_type(tok[2]);
    p.type = parse_type(tok[3]);
    p.name = tok[4];
    if (p.count_type == Type::kBad || p.count_type == Type::kFloat32 || p.count_type == Type::kFloat64)
      return text_error(path, ln, "bad list count type '" + std::string(tok[2]) + "'");
  } else if (tok.size() == 3) {
    p.type = parse_type(tok[1]);
    p.name = tok[2];
  } else {
    return text_error(path, ln, "expected 'property <type> <name>' or a list property");
  }
  if (p.type == Type::kBad) return text_error(path, ln, "unknown property type");
  return p;
}

// The header, up to end_header; "comment glimpse_sensor ..." and "comment glimpse_frame ..." lines set *view.
Expected<PlyHeader> read_header(const std::string& path, LineCursor& lines, Cloud* view) {
  std::string_view line;
  std::vector<std::string_view> tok;
  if (!lines.next(line) || trim(line) != "ply") return text_error(path, 1, "missing 'ply' header");
  PlyHeader h;
  bool have_format = false, ended = false;
  while (!ended && lines.next(line)) {
    split(line, tok);
    if (tok.empty()) continue;
    const size_t ln = lines.line_no();
    if (tok[0] == "comment" || tok[0] == "obj_info") {
      if (view && tok[0] == "comment") parse_view_comment(trim(line).substr(7), *view);
    } else if (tok[0] == "format") {
      if (tok.size() < 2) return text_error(path, ln, "incomplete format line");
      if (tok[1] == "ascii") h.format = Format::kAscii;
      else if (tok[1] == "binary_little_endian") h.format = Format::kLittle;
      else if (tok[1] == "binary_big_endian") h.format = Format::kBig;
      else return text_error(path, ln, "unknown format '" + std::string(tok[1]) + "'");
      have_format = true;
    } else if (tok[0] == "element") {
      Element e;
      if (tok.size() != 3 || !parse_u64(tok[2], e.count)) return text_error(path, ln, "expected 'element <name> <count>'");
      e.name = tok[1];
      e.header_line = ln;
      h.elements.push_back(std::move(e));
    } else if (tok[0] == "property") {
      if (h.elements.empty()) return text_error(path, ln, "property before any element");
      auto p = read_property(path, ln, tok);
      if (!p) return p.error();
      h.elements.back().props.push_back(std::move(*p));
    } else if (tok[0] == "end_header") {
      ended = true;
    } else {
      return text_error(path, ln, "unexpected header line '" + std::string(tok[0]) + "'");
    }
  }
  if (!ended) return text_error(path, lines.line_no(), "missing end_header");
  if (!have_format) return text_error(path, lines.line_no(), "missing format line");
  return h;
}

// Which properties of an element are x, y, z and the face's index list (-1: none).
struct ElementRoles {
  int xyz[3] = {-1, -1, -1};
  int index_prop = -1;
};
ElementRoles element_roles(const Element& e) {
  ElementRoles r;
  for (size_t k = 0; k < e.props.size(); ++k) {
    const Property& p = e.props[k];
    for (int a = 0; a < 3; ++a)
      if (!p.is_list && p.name == std::string(1, char('x' + a))) r.xyz[a] = int(k);
    if (is_index_list(p)) r.index_prop = int(k);
  }
  return r;
}

// One list property's values; the face's index list (`keep`) fan-triangulated into mesh.faces.
Status read_list(Body& body, const Property& p, bool keep, std::vector<int>& polygon, Mesh& mesh) {
  Error error;
  double v = 0;
  if (!body.read(p.count_type, v, error)) return error;
  if (v < 0 || v != std::floor(v) || v * double(body.min_bytes(p.type)) > double(body.remaining()))
    return body.where("bad list length " + std::to_string(v));
  const auto n = static_cast<uint64_t>(v);
  if (keep && n < 3) return body.where("a face needs at least 3 vertices");
  polygon.clear();
  for (uint64_t j = 0; j < n; ++j) {
    if (!body.read(p.type, v, error)) return error;
    if (keep) {
      if (v < 0 || v >= 2147483647.0 || v != std::floor(v)) return body.where("bad vertex index " + std::to_string(v));
      polygon.push_back(static_cast<int>(v));
    }
  }
  if (keep) {
    if (mesh.faces.size() + n > kMaxFaces) return body.where("too many faces");
    add_fan(polygon, mesh.faces);
  }
  return {};
}

// Every item of element `e`: vertices into mesh.vertices, faces (unless vertices_only) into mesh.faces,
// other elements read past.
Status read_element(const std::string& path, Body& body, Format format, const Element& e, bool vertices_only,
                    Mesh& mesh) {
  const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
  // Refuse counts the remaining bytes cannot hold: each item needs its fixed-size part (binary)
  // or two characters per property (ascii).
  uint64_t min_bytes = 0;
  for (const Property& p : e.props)
    min_bytes += format == Format::kAscii ? 2 : (p.is_list ? type_size(p.count_type) : type_size(p.type));
  const uint64_t limit = is_vertex ? kMaxPoints : kMaxFaces;
  if (e.count > limit || (min_bytes > 0 && e.count > (body.remaining() + 1) / min_bytes))
    return text_error(path, e.header_line, "element '" + e.name + "' count " + std::to_string(e.count) +
                                               " exceeds what the file can hold");
  const ElementRoles roles = element_roles(e);
  if (is_vertex) {
    if (roles.xyz[0] < 0 || roles.xyz[1] < 0 || roles.xyz[2] < 0)
      return text_error(path, e.header_line, "vertex element lacks x, y or z");
    mesh.vertices.reserve(e.count);
  }
  if (is_face && !vertices_only && roles.index_prop < 0)
    return text_error(path, e.header_line, "face element lacks a vertex_indices list");
  std::vector<int> polygon;
  Error error;
  for (uint64_t i = 0; i < e.count; ++i) {
    double xyzv[3] = {0, 0, 0};
    body.begin_item(e.name, e.props.size());
    for (size_t k = 0; k < e.props.size(); ++k) {
      const Property& p = e.props[k];
      if (p.is_list) {
        const bool keep = is_face && int(k) == roles.index_prop && !vertices_only;
        if (Status s = read_list(body, p, keep, polygon, mesh); !s) return s;
        continue;
      }
      double v = 0;
      if (!body.read(p.type, v, error)) return error;
      for (int a = 0; a < 3; ++a)
        if (roles.xyz[a] == int(k)) xyzv[a] = v;
    }
    if (!body.end_item(error)) return error;
    if (is_vertex) mesh.vertices.emplace_back(float(xyzv[0]), float(xyzv[1]), float(xyzv[2]));
  }
  return {};
}

}  // namespace

Expected<Mesh> read_ply(const std::string& path, std::string_view text, bool vertices_only, Cloud* view) {
  LineCursor lines(text);
  auto header = read_header(path, lines, view);
  if (!header) return header.error();
  Body body(path, text, lines.offset(), lines.line_no() + 1, header->format);
  Mesh mesh;
  uint64_t vertex_count = 0;
  bool have_vertices = false;
  for (const Element& e : header->elements) {
    if (vertices_only && have_vertices) break;
    if (Status s = read_element(path, body, header->format, e, vertices_only, mesh); !s) return s.error();
    if (e.name == "vertex") vertex_count = e.count, have_vertices = true;
  }
  if (!have_vertices) return text_error(path, lines.line_no(), "no vertex element");
  for (const Eigen::Vector3i& f : mesh.faces)
    for (int a = 0; a < 3; ++a)
      if (static_cast<uint64_t>(f[a]) >= vertex_count)
        return data_loss(path + ": face index " + std::to_string(f[a]) + " out of range (" +
                         std::to_string(vertex_count) + " vertices)");
  return mesh;
}

Status write_ply(const std::string& path, const Cloud& cloud) {
  std::string s = "ply\nformat binary_little_endian 1.0\ncomment written by glimpse\n";
  append_view_comments(s, cloud, "comment ");
  s += "element vertex " + std::to_string(cloud.points.size()) +
       "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  const size_t header = s.size();
  s.resize(header + cloud.points.size() * 12);
  char* out = s.data() + header;
  for (const Vec3& p : cloud.points) {
    for (int a = 0; a < 3; ++a) {
      uint32_t bits = std::bit_cast<uint32_t>(p[a]);
      if constexpr (std::endian::native == std::endian::big) bits = __builtin_bswap32(bits);
      std::memcpy(out, &bits, 4);
      out += 4;
    }
  }
  return write_bytes(path, s);
}

}  // namespace glimpse::io_detail

// PCD (Point Cloud Library file format v0.7): ascii and binary bodies; binary_compressed is refused.
#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "io/text.h"

namespace glimpse::io_detail {
namespace {

struct Field {
  std::string name;
  uint64_t size = 4;
  char type = 'F';
  uint64_t count = 1;
  uint64_t offset = 0;  // bytes into a binary point record
  uint64_t column = 0;  // token index in an ascii point line
};

// One binary value (host is little-endian on every platform we build for; PCD binary is host order).
bool decode(const char* p, const Field& f, double& out) {
  switch (f.type) {
    case 'F':
      if (f.size == 4) { float v; std::memcpy(&v, p, 4); out = v; return true; }
      if (f.size == 8) { double v; std::memcpy(&v, p, 8); out = v; return true; }
      return false;
    case 'I':
      if (f.size == 1) { int8_t v; std::memcpy(&v, p, 1); out = v; return true; }
      if (f.size == 2) { int16_t v; std::memcpy(&v, p, 2); out = v; return true; }
      if (f.size == 4) { int32_t v; std::memcpy(&v, p, 4); out = v; return true; }
      if (f.size == 8) { int64_t v; std::memcpy(&v, p, 8); out = double(v); return true; }
      return false;
    case 'U':
      if (f.size == 1) { uint8_t v; std::memcpy(&v, p, 1); out = v; return true; }
      if (f.size == 2) { uint16_t v; std::memcpy(&v, p, 2); out = v; return true; }
      if (f.size == 4) { uint32_t v; std::memcpy(&v, p, 4); out = v; return true; }
      if (f.size == 8) { uint64_t v; std::memcpy(&v, p, 8); out = double(v); return true; }
      return false;
  }
  return false;
}

}  // namespace

Expected<Cloud> read_pcd(const std::string& path, std::string_view text) {
  LineCursor lines(text);
  std::string_view line;
  std::vector<std::string_view> tok;
  std::vector<Field> fields;
  uint64_t width = 0, height = 1, points = 0;
  bool have_points = false, have_width = false, have_data = false, binary = false;
  Cloud cloud;
  std::optional<Vec3> commented_sensor;  // "# glimpse_sensor x y z": says "at the origin" too
  auto per_field = [&](size_t ln, auto&& set) -> Status {
    if (tok.size() != fields.size() + 1)
      return text_error(path, ln, std::string(tok[0]) + " needs one value per field");
    for (size_t k = 0; k < fields.size(); ++k)
      if (!set(fields[k], tok[k + 1])) return text_error(path, ln, "bad " + std::string(tok[0]) + " value");
    return {};
  };
  while (!have_data && lines.next(line)) {
    if (const std::string_view raw = trim(line); !raw.empty() && raw.front() == '#') {
      Vec3 s;
      if (parse_sensor_comment(raw.substr(1), s)) commented_sensor = s;
      continue;
    }
    split(strip_comment(line), tok);
    if (tok.empty()) continue;
    const size_t ln = lines.line_no();
    const std::string key = lower(tok[0]);
    Status st;
    if (key == "version") {
    } else if (key == "fields") {
      fields.clear();
      for (size_t k = 1; k < tok.size(); ++k) fields.push_back(Field{std::string(tok[k])});
    } else if (key == "size") {
      st = per_field(ln, [](Field& f, std::string_view t) { return parse_u64(t, f.size); });
    } else if (key == "type") {
      st = per_field(ln, [](Field& f, std::string_view t) {
        f.type = t.size() == 1 ? t[0] : '?';
        return f.type == 'F' || f.type == 'I' || f.type == 'U';
      });
    } else if (key == "count") {
      st = per_field(ln, [](Field& f, std::string_view t) { return parse_u64(t, f.count) && f.count > 0; });
    } else if (key == "width") {
      if (tok.size() != 2 || !parse_u64(tok[1], width)) return text_error(path, ln, "bad WIDTH");
      have_width = true;
    } else if (key == "height") {
      if (tok.size() != 2 || !parse_u64(tok[1], height) || height == 0)
        return text_error(path, ln, "bad HEIGHT (1 for an unorganised cloud)");
    } else if (key == "points") {
      if (tok.size() != 2 || !parse_u64(tok[1], points)) return text_error(path, ln, "bad POINTS");
      have_points = true;
    } else if (key == "viewpoint") {
      double v[7];
      if (tok.size() != 8) return text_error(path, ln, "VIEWPOINT needs 7 numbers");
      for (int i = 0; i < 7; ++i)
        if (!parse_double(tok[1 + i], v[i])) return text_error(path, ln, "bad VIEWPOINT value");
      const bool identity = v[0] == 0 && v[1] == 0 && v[2] == 0 && v[3] == 1 && v[4] == 0 && v[5] == 0 && v[6] == 0;
      if (!identity) cloud.sensor = Vec3(float(v[0]), float(v[1]), float(v[2]));
    } else if (key == "data") {
      if (tok.size() != 2) return text_error(path, ln, "bad DATA line");
      const std::string kind = lower(tok[1]);
      if (kind == "binary_compressed")
        return invalid_argument(path + ":" + std::to_string(ln) +
                                ": DATA binary_compressed is not supported; save as ascii or binary");
      if (kind != "ascii" && kind != "binary") return text_error(path, ln, "unknown DATA '" + kind + "'");
      binary = kind == "binary";
      have_data = true;
    } else {
      return text_error(path, ln, "unknown header line '" + std::string(tok[0]) + "'");
    }
    if (!st) return st.error();
  }
  if (!have_data) return text_error(path, lines.line_no(), "missing DATA line (not a PCD file?)");
  if (have_width && width > kMaxPoints / height) return text_error(path, lines.line_no(), "WIDTH*HEIGHT too large");
  if (!have_points) {
    points = width * height;
  } else if (have_width && points != width * height) {
    // Which one is the cloud? PCL refuses the file too; reading either would silently cut or pad it.
    return text_error(path, lines.line_no(), "POINTS " + std::to_string(points) + " but WIDTH x HEIGHT is " +
                                                 std::to_string(width * height));
  }
  if (commented_sensor) cloud.sensor = commented_sensor;
  int xyz[3] = {-1, -1, -1};
  uint64_t offset = 0, column = 0;
  for (size_t k = 0; k < fields.size(); ++k) {
    Field& f = fields[k];
    if (f.size == 0 || f.size > 8 || f.count > 1'000'000)
      return text_error(path, lines.line_no(), "bad SIZE or COUNT for field '" + f.name + "'");
    f.offset = offset;
    f.column = column;
    offset += f.size * f.count;
    column += f.count;
    for (int a = 0; a < 3; ++a)
      if (f.name == std::string(1, char('x' + a))) xyz[a] = int(k);
  }
  if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0)
    return text_error(path, lines.line_no(), "FIELDS lacks x, y or z");
  const size_t data_line = lines.line_no();
  const uint64_t min_bytes = binary ? offset : 2 * column;
  // Ascii: the last line may lack its newline. Binary: every record is whole (no +1, or the last one
  // would be read a byte past the end).
  if (points > kMaxPoints || points > (lines.remaining() + (binary ? 0 : 1)) / min_bytes)
    return text_error(path, data_line, "POINTS " + std::to_string(points) + " exceeds what the file can hold");
  cloud.points.reserve(points);
  if (binary) {
    const size_t start = lines.offset();
    // A header that says binary over a text body would read its digits as floats, silently: the first
    // records all digits, signs, points and blanks are text (no float32 triple is made of those alone).
    const uint64_t probe = std::min<uint64_t>(points, 4) * offset;
    const bool text_body = probe > 0 && std::all_of(text.begin() + std::ptrdiff_t(start),
                                                    text.begin() + std::ptrdiff_t(start + probe), [](char ch) {
                                                      return (ch >= '0' && ch <= '9') || ch == ' ' || ch == '.' || ch == '-' ||
                                                             ch == '+' || ch == 'e' || ch == 'E' || ch == '\n' ||
                                                             ch == '\r' || ch == '\t';
                                                    });
    if (text_body) return byte_error(path, start, "DATA binary, but the body is text: is it DATA ascii?");
    for (uint64_t i = 0; i < points; ++i) {
      const char* rec = text.data() + start + i * offset;
      double v[3];
      for (int a = 0; a < 3; ++a)
        if (!decode(rec + fields[xyz[a]].offset, fields[xyz[a]], v[a]))
          return byte_error(path, start + i * offset, "unsupported SIZE/TYPE for field '" + fields[xyz[a]].name + "'");
      cloud.points.emplace_back(float(v[0]), float(v[1]), float(v[2]));
    }
    return cloud;
  }
  while (cloud.points.size() < points) {
    if (!lines.next(line))
      return text_error(path, lines.line_no(), "truncated: expected " + std::to_string(points) +
                                                   " points, found " + std::to_string(cloud.points.size()));
    split(line, tok);
    if (tok.empty()) continue;
    if (tok.size() != column)
      return text_error(path, lines.line_no(), "expected " + std::to_string(column) + " values (FIELDS and COUNT), found " +
                                                   std::to_string(tok.size()));
    double v[3];
    for (int a = 0; a < 3; ++a)
      if (!parse_double(tok[fields[xyz[a]].column], v[a]))
        return text_error(path, lines.line_no(), "not a number: '" + std::string(tok[fields[xyz[a]].column]) + "'");
    cloud.points.emplace_back(float(v[0]), float(v[1]), float(v[2]));
  }
  while (lines.next(line))  // more points than the header says: which count is the cloud's?
    if (split(line, tok); !tok.empty())
      return text_error(path, lines.line_no(), "data after the " + std::to_string(points) + " points the header declares");
  return cloud;
}

Status write_pcd(const std::string& path, const Cloud& cloud) {
  const std::string n = std::to_string(cloud.points.size());
  std::string s = "# .PCD v0.7 - Point Cloud Data file format (written by glimpse)\n";
  if (cloud.sensor) {  // the comment keeps a sensor at the origin, which VIEWPOINT alone cannot say
    s += "# glimpse_sensor ";
    for (int a = 0; a < 3; ++a) {
      append_float(s, (*cloud.sensor)[a]);
      s += a < 2 ? ' ' : '\n';
    }
  }
  s += "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " + n + "\nHEIGHT 1\n";
  s += "VIEWPOINT ";
  if (cloud.sensor) {
    for (int a = 0; a < 3; ++a) {
      append_float(s, (*cloud.sensor)[a]);
      s += ' ';
    }
    s += "1 0 0 0\n";
  } else {
    s += "0 0 0 1 0 0 0\n";
  }
  s += "POINTS " + n + "\nDATA ascii\n";
  s.reserve(s.size() + cloud.points.size() * 30);
  for (const Vec3& p : cloud.points) {
    for (int a = 0; a < 3; ++a) {
      append_float(s, p[a]);
      s += a < 2 ? ' ' : '\n';
    }
  }
  return write_bytes(path, s);
}

}  // namespace glimpse::io_detail

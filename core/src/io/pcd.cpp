// PCD (Point Cloud Library file format v0.7): the header, ascii and binary bodies; binary_compressed bodies
// go through PCL (pcd_compressed.cpp).
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

using Field = PcdField;

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

// What a PCD header declares.
struct PcdHeader {
  std::vector<Field> fields;
  uint64_t width = 0, height = 1, points = 0;
  bool have_points = false, have_width = false, binary = false, compressed = false;
  std::optional<Vec3> sensor;            // VIEWPOINT, when not the identity
  Cloud commented;  // "# glimpse_sensor x y z" (says "at the origin" too) and "# glimpse_frame ..." comments
  double viewpoint[7] = {0, 0, 0, 1, 0, 0, 0};  // VIEWPOINT: translation, then rotation w x y z
};

// One header line (its tokens `tok`, of line `ln`) into `h`; `data` is set on the DATA line.
Status read_header_line(const std::string& path, size_t ln, const std::vector<std::string_view>& tok, PcdHeader& h,
                        bool& data) {
  auto per_field = [&](auto&& set) -> Status {
    if (tok.size() != h.fields.size() + 1) return text_error(path, ln, std::string(tok[0]) + " needs one value per field");
    for (size_t k = 0; k < h.fields.size(); ++k)
      if (!set(h.fields[k], tok[k + 1])) return text_error(path, ln, "bad " + std::string(tok[0]) + " value");
    return {};
  };
  const std::string key = lower(tok[0]);
  if (key == "version") return {};
  if (key == "fields") {
    h.fields.clear();
    for (size_t k = 1; k < tok.size(); ++k) h.fields.push_back(Field{std::string(tok[k])});
    return {};
  }
  if (key == "size") return per_field([](Field& f, std::string_view t) { return parse_u64(t, f.size); });
  if (key == "type")
    return per_field([](Field& f, std::string_view t) {
      f.type = t.size() == 1 ? t[0] : '?';
      return f.type == 'F' || f.type == 'I' || f.type == 'U';
    });
  if (key == "count") return per_field([](Field& f, std::string_view t) { return parse_u64(t, f.count) && f.count > 0; });
  if (key == "width") {
    if (tok.size() != 2 || !parse_u64(tok[1], h.width)) return text_error(path, ln, "bad WIDTH");
    h.have_width = true;
    return {};
  }
  if (key == "height") {
    if (tok.size() != 2 || !parse_u64(tok[1], h.height) || h.height == 0)
      return text_error(path, ln, "bad HEIGHT (1 for an unorganised cloud)");
    return {};
  }
  if (key == "points") {
    if (tok.size() != 2 || !parse_u64(tok[1], h.points)) return text_error(path, ln, "bad POINTS");
    h.have_points = true;
    return {};
  }
  if (key == "viewpoint") {
    double v[7];
    if (tok.size() != 8) return text_error(path, ln, "VIEWPOINT needs 7 numbers");
    for (int i = 0; i < 7; ++i)
      if (!parse_double(tok[1 + i], v[i])) return text_error(path, ln, "bad VIEWPOINT value");
    std::copy(v, v + 7, h.viewpoint);
    const bool identity = v[0] == 0 && v[1] == 0 && v[2] == 0 && v[3] == 1 && v[4] == 0 && v[5] == 0 && v[6] == 0;
    if (!identity) h.sensor = Vec3(float(v[0]), float(v[1]), float(v[2]));
    return {};
  }
  if (key == "data") {
    if (tok.size() != 2) return text_error(path, ln, "bad DATA line");
    const std::string kind = lower(tok[1]);
    if (kind != "ascii" && kind != "binary" && kind != "binary_compressed")
      return text_error(path, ln, "unknown DATA '" + kind + "'");
    h.binary = kind == "binary";
    h.compressed = kind == "binary_compressed";
    data = true;
    return {};
  }
  return text_error(path, ln, "unknown header line '" + std::string(tok[0]) + "'");
}

// The header, up to and including its DATA line; POINTS checked against WIDTH x HEIGHT.
Expected<PcdHeader> read_header(const std::string& path, LineCursor& lines) {
  PcdHeader h;
  std::string_view line;
  std::vector<std::string_view> tok;
  bool data = false;
  while (!data && lines.next(line)) {
    if (const std::string_view raw = trim(line); !raw.empty() && raw.front() == '#') {
      parse_view_comment(raw.substr(1), h.commented);
      continue;
    }
    split(strip_comment(line), tok);
    if (tok.empty()) continue;
    if (Status st = read_header_line(path, lines.line_no(), tok, h, data); !st) return st.error();
  }
  if (!data) return text_error(path, lines.line_no(), "missing DATA line (not a PCD file?)");
  if (h.have_width && h.width > kMaxPoints / h.height) return text_error(path, lines.line_no(), "WIDTH*HEIGHT too large");
  if (!h.have_points) {
    h.points = h.width * h.height;
  } else if (h.have_width && h.points != h.width * h.height) {
    // Which one is the cloud? PCL refuses the file too; reading either would silently cut or pad it.
    return text_error(path, lines.line_no(), "POINTS " + std::to_string(h.points) + " but WIDTH x HEIGHT is " +
                                                 std::to_string(h.width * h.height));
  }
  return h;
}

// Where each field lies in a binary record (offset) and an ascii line (column), and which fields are
// x, y, z; the record's bytes and the line's values.
struct Layout {
  int xyz[3] = {-1, -1, -1};
  uint64_t record_bytes = 0, columns = 0;
};
Expected<Layout> field_layout(const std::string& path, size_t ln, std::vector<Field>& fields) {
  Layout l;
  for (size_t k = 0; k < fields.size(); ++k) {
    Field& f = fields[k];
    if (f.size == 0 || f.size > 8 || f.count > 1'000'000)
      return text_error(path, ln, "bad SIZE or COUNT for field '" + f.name + "'");
    f.offset = l.record_bytes;
    f.column = l.columns;
    l.record_bytes += f.size * f.count;
    l.columns += f.count;
    for (int a = 0; a < 3; ++a)
      if (f.name == std::string(1, char('x' + a))) l.xyz[a] = int(k);
  }
  if (l.xyz[0] < 0 || l.xyz[1] < 0 || l.xyz[2] < 0) return text_error(path, ln, "FIELDS lacks x, y or z");
  return l;
}

// x, y, z of `points` records of layout.record_bytes from byte `start` of `bytes`.
Status read_records(const std::string& path, std::string_view bytes, size_t start, const PcdHeader& h,
                    const Layout& layout, Cloud& cloud) {
  const uint64_t record = layout.record_bytes;
  for (uint64_t i = 0; i < h.points; ++i) {
    const char* rec = bytes.data() + start + i * record;
    double v[3];
    for (int a = 0; a < 3; ++a) {
      const Field& f = h.fields[size_t(layout.xyz[a])];
      if (!decode(rec + f.offset, f, v[a]))
        return byte_error(path, start + i * record, "unsupported SIZE/TYPE for field '" + f.name + "'");
    }
    cloud.points.emplace_back(float(v[0]), float(v[1]), float(v[2]));
  }
  return {};
}

// A binary body from byte `start`: `points` records of layout.record_bytes.
Status read_binary_body(const std::string& path, std::string_view text, size_t start, const PcdHeader& h,
                        const Layout& layout, Cloud& cloud) {
  const uint64_t record = layout.record_bytes;
  // A header that says binary over a text body would read its digits as floats, silently: the first
  // records all digits, signs, points and blanks are text (no float32 triple is made of those alone).
  const uint64_t probe = std::min<uint64_t>(h.points, 4) * record;
  const bool text_body = probe > 0 && std::all_of(text.begin() + std::ptrdiff_t(start),
                                                  text.begin() + std::ptrdiff_t(start + probe), [](char ch) {
                                                    return (ch >= '0' && ch <= '9') || ch == ' ' || ch == '.' || ch == '-' ||
                                                           ch == '+' || ch == 'e' || ch == 'E' || ch == '\n' ||
                                                           ch == '\r' || ch == '\t';
                                                  });
  if (text_body) return byte_error(path, start, "DATA binary, but the body is text: is it DATA ascii?");
  return read_records(path, text, start, h, layout, cloud);
}

// A binary_compressed body from byte `start`, unpacked by PCL into binary records. Its x, y and z are
// checked before: an error's byte offset then always lies in the file.
Status read_compressed(const std::string& path, std::string_view text, size_t start, size_t data_line,
                       const PcdHeader& h, const Layout& layout, Cloud& cloud) {
  for (int a = 0; a < 3; ++a) {
    const Field& f = h.fields[size_t(layout.xyz[a])];
    const char zeros[8] = {};
    double v;
    if (!decode(zeros, f, v)) return text_error(path, data_line, "unsupported SIZE/TYPE for field '" + f.name + "'");
  }
  Expected<std::string> records = read_compressed_body(path, text, start, h.fields, h.points, layout.record_bytes);
  if (!records) return records.error();
  return read_records(path, *records, 0, h, layout, cloud);
}

// An ascii body: one line of exactly layout.columns values per point, nothing after the last point.
Status read_ascii_body(const std::string& path, LineCursor& lines, const PcdHeader& h, const Layout& layout,
                       Cloud& cloud) {
  std::string_view line;
  std::vector<std::string_view> tok;
  while (cloud.points.size() < h.points) {
    if (!lines.next(line))
      return text_error(path, lines.line_no(), "truncated: expected " + std::to_string(h.points) +
                                                   " points, found " + std::to_string(cloud.points.size()));
    split(line, tok);
    if (tok.empty()) continue;
    if (tok.size() != layout.columns)
      return text_error(path, lines.line_no(), "expected " + std::to_string(layout.columns) +
                                                   " values (FIELDS and COUNT), found " + std::to_string(tok.size()));
    double v[3];
    for (int a = 0; a < 3; ++a) {
      const std::string_view t = tok[h.fields[size_t(layout.xyz[a])].column];
      if (!parse_double(t, v[a])) return text_error(path, lines.line_no(), "not a number: '" + std::string(t) + "'");
    }
    cloud.points.emplace_back(float(v[0]), float(v[1]), float(v[2]));
  }
  while (lines.next(line))  // more points than the header says: which count is the cloud's?
    if (split(line, tok); !tok.empty())
      return text_error(path, lines.line_no(), "data after the " + std::to_string(h.points) + " points the header declares");
  return {};
}

}  // namespace

Expected<Cloud> read_pcd(const std::string& path, std::string_view text, double* viewpoint) {
  LineCursor lines(text);
  auto header = read_header(path, lines);
  if (!header) return header.error();
  PcdHeader& h = *header;
  // PCL's writer leaves '_' (padding) fields out of a compressed body, and its reader skips them.
  if (h.compressed) std::erase_if(h.fields, [](const Field& f) { return f.name == "_"; });
  auto layout = field_layout(path, lines.line_no(), h.fields);
  if (!layout) return layout.error();
  Cloud cloud;
  cloud.sensor = h.commented.sensor ? h.commented.sensor : h.sensor;
  cloud.frame = h.commented.frame;
  if (viewpoint) std::copy(h.viewpoint, h.viewpoint + 7, viewpoint);
  const size_t data_line = lines.line_no();
  // Ascii: the last line may lack its newline. Binary: every record is whole (no +1, or the last one
  // would be read a byte past the end). Compressed: LZF expands at most kLzfMaxExpansion times.
  const uint64_t room = h.compressed ? lines.remaining() * kLzfMaxExpansion / layout->record_bytes
                        : h.binary   ? lines.remaining() / layout->record_bytes
                                     : (lines.remaining() + 1) / (2 * layout->columns);
  if (h.points > kMaxPoints || h.points > room)
    return text_error(path, data_line, "POINTS " + std::to_string(h.points) + " exceeds what the file can hold" +
                                           (h.compressed ? " (a truncated binary_compressed body?)" : ""));
  cloud.points.reserve(h.points);
  const Status body = h.compressed ? read_compressed(path, text, lines.offset(), data_line, h, *layout, cloud)
                      : h.binary   ? read_binary_body(path, text, lines.offset(), h, *layout, cloud)
                                   : read_ascii_body(path, lines, h, *layout, cloud);
  if (!body) return body.error();
  return cloud;
}

Status write_pcd(const std::string& path, const Cloud& cloud) {
  const std::string n = std::to_string(cloud.points.size());
  std::string s = "# .PCD v0.7 - Point Cloud Data file format (written by glimpse)\n";
  append_view_comments(s, cloud, "# ");  // the sensor comment says "at the origin", which VIEWPOINT cannot
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

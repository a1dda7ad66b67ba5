// Format dispatch, shared parsing helpers and the plain XYZ format. The other formats live in
// off.cpp (OFF, OBJ), ply.cpp, stl.cpp, pcd.cpp and pcd_compressed.cpp.
#include "glimpse/io/files.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <new>

#include "io/text.h"

namespace glimpse {
namespace io_detail {

Expected<std::string> read_file(const std::string& path) {
  std::error_code ec;
  const std::filesystem::path p(path);
  if (!std::filesystem::exists(p, ec)) return not_found(path + ": no such file");
  if (std::filesystem::is_directory(p, ec)) return invalid_argument(path + ": is a directory");
  std::ifstream in(p, std::ios::binary);
  if (!in) return not_found(path + ": cannot open for reading");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) return data_loss(path + ": cannot determine the file size");
  if (static_cast<uint64_t>(size) > kMaxFileBytes)
    return resource_exhausted(path + ": file larger than " + std::to_string(kMaxFileBytes) + " bytes");
  in.seekg(0, std::ios::beg);
  std::string data(static_cast<size_t>(size), '\0');
  if (size > 0 && !in.read(data.data(), size)) return data_loss(path + ": read failed");
  return data;
}

bool LineCursor::next(std::string_view& line) {
  if (pos_ >= text_.size()) return false;
  // A line ends at "\n", "\r\n" or a lone "\r" (classic Mac files, which would otherwise read as one line).
  size_t end = pos_;
  while (end < text_.size() && text_[end] != '\n' && text_[end] != '\r') ++end;
  line = text_.substr(pos_, end - pos_);
  pos_ = end;
  if (pos_ < text_.size() && text_[pos_] == '\r') ++pos_;
  if (pos_ < text_.size() && text_[pos_] == '\n' && (pos_ == end || text_[end] == '\r')) ++pos_;
  ++line_no_;
  return true;
}

std::string_view trim(std::string_view s) {
  const char* blanks = " \t\r\n\f\v";
  const size_t b = s.find_first_not_of(blanks);
  if (b == std::string_view::npos) return {};
  const size_t e = s.find_last_not_of(blanks);
  return s.substr(b, e - b + 1);
}

std::string_view strip_comment(std::string_view line, char mark) {
  const size_t c = line.find(mark);
  if (c != std::string_view::npos) line = line.substr(0, c);
  return trim(line);
}

void split(std::string_view line, std::vector<std::string_view>& out, bool commas) {
  out.clear();
  size_t i = 0;
  auto is_sep = [&](char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v' || (commas && c == ',');
  };
  while (i < line.size()) {
    while (i < line.size() && is_sep(line[i])) ++i;
    const size_t b = i;
    while (i < line.size() && !is_sep(line[i])) ++i;
    if (i > b) out.push_back(line.substr(b, i - b));
  }
}

bool parse_double(std::string_view t, double& out) {
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  if (t.empty()) return false;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), out);
  return r.ec == std::errc() && r.ptr == t.data() + t.size();
}

bool parse_u64(std::string_view t, uint64_t& out) {
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  if (t.empty()) return false;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), out);
  return r.ec == std::errc() && r.ptr == t.data() + t.size();
}

bool parse_i64(std::string_view t, int64_t& out) {
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  if (t.empty()) return false;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), out);
  return r.ec == std::errc() && r.ptr == t.data() + t.size();
}

std::string lower(std::string_view s) {
  std::string r(s);
  for (char& c : r) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return r;
}

void append_float(std::string& out, float v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

void add_fan(const std::vector<int>& polygon, std::vector<Eigen::Vector3i>& faces) {
  for (size_t k = 1; k + 1 < polygon.size(); ++k)
    faces.emplace_back(polygon[0], polygon[k], polygon[k + 1]);
}

Status write_bytes(const std::string& path, const std::string& data) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return not_found(path + ": cannot open for writing");
  out.write(data.data(), static_cast<std::streamsize>(data.size()));
  out.close();
  if (!out) return internal_error(path + ": write failed");
  return {};
}

bool parse_view_comment(std::string_view comment, Cloud& view) {
  std::vector<std::string_view> tok;
  split(comment, tok);
  const bool sensor = tok.size() == 4 && tok[0] == "glimpse_sensor", frame = tok.size() == 9 && tok[0] == "glimpse_frame";
  if (!sensor && !frame) return false;
  double v[8];
  for (size_t i = 1; i < tok.size(); ++i)
    if (!parse_double(tok[i], v[i - 1])) return false;
  if (sensor) view.sensor = Vec3(float(v[0]), float(v[1]), float(v[2]));
  if (frame)
    view.frame = CameraFrame{Vec3(float(v[0]), float(v[1]), float(v[2])), Vec3(float(v[3]), float(v[4]), float(v[5])),
                             float(v[6]), float(v[7])};
  return true;
}

void append_view_comments(std::string& out, const Cloud& cloud, std::string_view marker) {
  auto line = [&](const char* key, std::initializer_list<float> values) {
    out += marker;
    out += key;
    for (float v : values) out += ' ', append_float(out, v);
    out += '\n';
  };
  if (cloud.sensor) line("glimpse_sensor", {cloud.sensor->x(), cloud.sensor->y(), cloud.sensor->z()});
  if (const auto& f = cloud.frame)
    line("glimpse_frame", {f->axis.x(), f->axis.y(), f->axis.z(), f->up.x(), f->up.y(), f->up.z(), f->fov_h_deg, f->fov_v_deg});
}

namespace {

// Plain text: x y z [more columns] per line, blanks or commas, '#' comments; one header row allowed.
Expected<Cloud> read_xyz(const std::string& path, std::string_view text) {
  Cloud cloud;
  LineCursor lines(text);
  std::string_view line;
  std::vector<std::string_view> tok;
  bool seen_data = false;
  while (lines.next(line)) {
    const std::string_view raw = trim(line);
    if (!raw.empty() && raw.front() == '#') {
      parse_view_comment(raw.substr(1), cloud);
      continue;
    }
    split(strip_comment(line), tok, /*commas=*/true);
    if (tok.empty()) continue;
    double v[3];
    bool ok = tok.size() >= 3;
    for (int i = 0; ok && i < 3; ++i) ok = parse_double(tok[i], v[i]);
    if (!ok) {
      // A column header such as "x,y,z": no number in it ("0x10 0 0" is a bad row, not a header).
      const bool header = std::none_of(tok.begin(), tok.end(), [](std::string_view t) {
        double v;
        return parse_double(t, v);
      });
      if (!seen_data && header) {
        seen_data = true;
        continue;
      }
      return text_error(path, lines.line_no(), "expected at least 3 numbers (x y z)");
    }
    seen_data = true;
    if (cloud.points.size() >= kMaxPoints)
      return resource_exhausted(path + ": more than " + std::to_string(kMaxPoints) + " points");
    cloud.points.emplace_back(float(v[0]), float(v[1]), float(v[2]));
  }
  return cloud;
}

Status write_xyz(const std::string& path, const Cloud& cloud) {
  std::string s;
  s.reserve(cloud.points.size() * 30 + 64);
  append_view_comments(s, cloud, "# ");
  for (const Vec3& p : cloud.points) {
    for (int i = 0; i < 3; ++i) {
      append_float(s, p[i]);
      s += i < 2 ? ' ' : '\n';
    }
  }
  return write_bytes(path, s);
}

std::string extension(const std::string& path) {
  return lower(std::filesystem::path(path).extension().string());
}

// A folder given where a file is wanted, named as such (its extension would say nothing useful).
Status not_a_folder(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return invalid_argument(path + ": is a folder, not a file");
  return {};
}

}  // namespace
}  // namespace io_detail

using namespace io_detail;

Expected<Mesh> read_mesh(const std::string& path) {
  try {
    if (Status s = not_a_folder(path); !s.ok()) return s.error();
    const std::string ext = extension(path);
    if (ext != ".off" && ext != ".obj" && ext != ".ply" && ext != ".stl")
      return invalid_argument(path + ": unknown mesh extension '" + ext + "' (want .off, .obj, .ply, .stl)");
    Expected<std::string> data = read_file(path);
    if (!data) return data.error();
    if (data->empty()) return data_loss(path + ": empty file");
    if (ext == ".off") return read_off(path, *data);
    if (ext == ".obj") return read_obj(path, *data);
    if (ext == ".stl") return read_stl(path, *data);
    return read_ply(path, *data, /*vertices_only=*/false, nullptr);
  } catch (const std::bad_alloc&) {
    return resource_exhausted(path + ": out of memory while reading");
  } catch (const std::exception& e) {
    return internal_error(path + ": " + e.what());
  }
}

Expected<Cloud> read_cloud(const std::string& path) {
  try {
    if (Status s = not_a_folder(path); !s.ok()) return s.error();
    const std::string ext = extension(path);
    const bool known = ext == ".pcd" || ext == ".ply" || ext == ".xyz" || ext == ".txt" ||
                       ext == ".csv" || ext == ".off" || ext == ".obj" || ext == ".stl";
    if (!known)
      return invalid_argument(path + ": unknown cloud extension '" + ext +
                              "' (want .pcd, .ply, .xyz, .txt, .csv, .off, .obj, .stl)");
    Expected<std::string> data = read_file(path);
    if (!data) return data.error();
    if (data->empty()) return data_loss(path + ": empty file");
    if (ext == ".pcd") return read_pcd(path, *data);
    if (ext == ".xyz" || ext == ".txt" || ext == ".csv") return read_xyz(path, *data);
    Cloud cloud;
    Expected<Mesh> mesh = ext == ".ply"   ? read_ply(path, *data, true, &cloud)
                          : ext == ".off" ? read_off(path, *data)
                          : ext == ".stl" ? read_stl(path, *data)
                                          : read_obj(path, *data);
    if (!mesh) return mesh.error();
    cloud.points = std::move(mesh->vertices);
    return cloud;
  } catch (const std::bad_alloc&) {
    return resource_exhausted(path + ": out of memory while reading");
  } catch (const std::exception& e) {
    return internal_error(path + ": " + e.what());
  }
}

Expected<Cloud> read_camera_view(const std::string& path, float fov_h_deg, float fov_v_deg) {
  if (!(fov_h_deg > 0 && fov_h_deg < 180 && fov_v_deg > 0 && fov_v_deg < 180))
    return invalid_argument(path + ": a camera's fields of view are in (0, 180) degrees, not " + std::to_string(fov_h_deg) +
                            " x " + std::to_string(fov_v_deg));
  if (extension(path) != ".pcd")
    return invalid_argument(path + ": a camera's pose comes from a PCD VIEWPOINT; this is not a .pcd file");
  Expected<std::string> data = read_file(path);
  if (!data) return data.error();
  if (data->empty()) return data_loss(path + ": empty file");
  double v[7];
  Expected<Cloud> cloud = read_pcd(path, *data, v);
  if (!cloud) return cloud.error();
  if (cloud->sensor && cloud->frame) return cloud;
  // PCL's OpenNI grabbers turn their frames' viewpoint half round x for their viewer; the points stay in
  // the camera's coordinates (z forward), where a camera looking along -z would see none of them.
  const bool openni_grabber = v[0] == 0 && v[1] == 0 && v[2] == 0 && v[3] == 0 && v[4] == 1 && v[5] == 0 && v[6] == 0;
  if (openni_grabber) v[3] = 1, v[4] = 0;
  const Eigen::Quaternionf q{static_cast<float>(v[3]), static_cast<float>(v[4]), static_cast<float>(v[5]), static_cast<float>(v[6])};
  if (!q.coeffs().allFinite() || !(q.norm() > 1e-6f))
    return data_loss(path + ": VIEWPOINT's rotation (w x y z) is not a rotation");
  const Eigen::Matrix3f r = q.normalized().toRotationMatrix();
  cloud->sensor = Vec3(float(v[0]), float(v[1]), float(v[2]));
  cloud->frame = CameraFrame{r * Vec3::UnitZ(), r * -Vec3::UnitY(), fov_h_deg, fov_v_deg};
  return cloud;
}

Status write_cloud(const std::string& path, const Cloud& cloud) {
  try {
    const std::string ext = extension(path);
    if (ext == ".pcd") return write_pcd(path, cloud);
    if (ext == ".ply") return write_ply(path, cloud);
    if (ext == ".xyz") return write_xyz(path, cloud);
    return invalid_argument(path + ": unknown cloud extension '" + ext + "' (want .pcd, .ply, .xyz)");
  } catch (const std::bad_alloc&) {
    return resource_exhausted(path + ": out of memory while writing");
  } catch (const std::exception& e) {
    return internal_error(path + ": " + e.what());
  }
}

}  // namespace glimpse

#include "client/frames.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <Eigen/Geometry>

#include "client/inputs.h"

namespace glimpse::client {

namespace fs = std::filesystem;

bool NaturalLess(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j]))) {
      size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      std::string x = a.substr(i, ie - i), y = b.substr(j, je - j);
      x.erase(0, std::min(x.find_first_not_of('0'), x.size()));
      y.erase(0, std::min(y.find_first_not_of('0'), y.size()));
      if (x.size() != y.size()) return x.size() < y.size();
      if (x != y) return x < y;
      i = ie, j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i, ++j;
    }
  }
  if (a.size() - i != b.size() - j) return a.size() - i < b.size() - j;
  return a < b;  // "f01" and "f1": a stable order all the same
}

namespace {

struct Pose {
  Vec3 position = Vec3::Zero();
  std::optional<Eigen::Quaternionf> rotation;  // set: the frame's points are in the sensor's frame
};

Expected<std::map<std::string, Pose>> ReadPoses(const fs::path& path) {
  std::map<std::string, Pose> poses;
  std::ifstream in(path);
  if (!in) return invalid_argument(path.string() + ": cannot be read");
  std::string line;
  for (int ln = 1; std::getline(in, line); ++ln) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cells;
    std::stringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    const std::string where = path.string() + ":" + std::to_string(ln) + ": ";
    if (ln == 1 && cells.size() > 1 && cells[1] == "x") {  // a header: its columns must be the ones read
      std::string header;
      for (std::string c : cells) {
        c.erase(0, c.find_first_not_of(" \t"));
        c.erase(c.find_last_not_of(" \t") + 1);
        header += (header.empty() ? "" : ",") + c;
      }
      // A quaternion written x,y,z,w read as w,x,y,z turns every frame the wrong way, silently.
      const std::string columns = header.substr(header.find(','));  // after the file's column
      if (columns != ",x,y,z" && columns != ",x,y,z,qw,qx,qy,qz")
        return invalid_argument(where + "the header must be file,x,y,z or file,x,y,z,qw,qx,qy,qz (w first), not '" +
                                header + "'");
      continue;
    }
    if (cells.size() != 4 && cells.size() != 8)
      return invalid_argument(where + "expected file,x,y,z or file,x,y,z,qw,qx,qy,qz, got " +
                              std::to_string(cells.size()) + " fields");
    double v[7];
    for (size_t k = 1; k < cells.size(); ++k) {
      char* end = nullptr;
      v[k - 1] = std::strtod(cells[k].c_str(), &end);
      if (cells[k].empty() || *end || !std::isfinite(v[k - 1]))
        return invalid_argument(where + "'" + cells[k] + "' is not a finite number");
    }
    Pose pose;
    pose.position = Vec3(float(v[0]), float(v[1]), float(v[2]));
    if (cells.size() == 8) {
      const Eigen::Quaterniond q(v[3], v[4], v[5], v[6]);
      if (std::abs(q.norm() - 1.0) > 1e-3)
        return invalid_argument(where + "the quaternion qw,qx,qy,qz must be a unit one (its norm is " +
                                std::to_string(q.norm()) + ")");
      pose.rotation = q.normalized().cast<float>();
    }
    if (!poses.emplace(cells[0], pose).second) return invalid_argument(where + "'" + cells[0] + "' is listed twice");
  }
  return poses;
}

}  // namespace

Expected<std::vector<Cloud>> LoadFrames(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return invalid_argument(dir + ": not a folder of frames");
  std::vector<std::string> names;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.empty() || name[0] == '.' || name == "poses.csv" || !e.is_regular_file() || !IsInputFile(name)) continue;
    names.push_back(name);
  }
  if (ec) return invalid_argument(dir + ": " + ec.message());
  std::sort(names.begin(), names.end(), NaturalLess);
  if (names.empty()) return invalid_argument(dir + ": no frame (.pcd, .ply, .xyz, .txt, .csv) in the folder");
  std::map<std::string, Pose> poses;
  const fs::path poses_path = fs::path(dir) / "poses.csv";
  if (fs::exists(poses_path, ec)) {
    auto read = ReadPoses(poses_path);
    if (!read.ok()) return read.error();
    poses = std::move(*read);
    for (const auto& [name, pose] : poses)
      if (std::find(names.begin(), names.end(), name) == names.end())
        return invalid_argument(poses_path.string() + ": '" + name + "' is not a frame of the folder");
  }
  std::vector<Cloud> frames;
  for (const std::string& name : names) {
    const std::string path = (fs::path(dir) / name).string();
    auto file = LoadFile(path);
    if (!file.ok()) return file.error();
    if (file->is_mesh) return invalid_argument(path + ": a frame is a point cloud, not a mesh");
    Cloud frame = std::move(file->cloud);
    RemoveNonFinite(frame);  // a depth camera's organised cloud marks missing returns with NaN
    if (const auto it = poses.find(name); it != poses.end()) {
      if (it->second.rotation)
        for (Vec3& p : frame.points) p = *it->second.rotation * p + it->second.position;
      frame.sensor = it->second.position;
    }
    if (!frame.sensor)
      return invalid_argument(path + ": a frame needs its sensor position (a PCD VIEWPOINT, a '" +
                              std::string("glimpse_sensor x y z' comment, or a line in poses.csv)"));
    frames.push_back(std::move(frame));
  }
  return frames;
}

std::vector<Cloud> FrameChunks(const std::vector<Cloud>& frames, size_t chunk_points) {
  std::vector<Cloud> chunks;
  for (const Cloud& frame : frames) {
    const size_t step = chunk_points ? chunk_points : std::max<size_t>(1, frame.points.size());
    size_t begin = 0;
    do {
      const size_t end = std::min(frame.points.size(), begin + step);
      Cloud c;
      c.sensor = frame.sensor;
      c.frame = frame.frame;
      c.points.assign(frame.points.begin() + std::ptrdiff_t(begin), frame.points.begin() + std::ptrdiff_t(end));
      chunks.push_back(std::move(c));
      begin = end;
    } while (begin < frame.points.size());
  }
  return chunks;
}

}  // namespace glimpse::client

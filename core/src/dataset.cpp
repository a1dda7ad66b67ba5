// Dataset manifest (DIR/<category>/<id>.off) and loading objects upright at real-life size (sec. 3.4).
#include "glimpse/dataset.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <new>
#include <random>

#include "glimpse/io.h"

namespace glimpse {
namespace {

namespace fs = std::filesystem;

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool is_mesh_file(const fs::path& p) {
  const std::string ext = lower(p.extension().string());
  return ext == ".off" || ext == ".obj" || ext == ".ply";
}

bool is_numeric(const std::string& s) {
  return !s.empty() && s.size() < 19 && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// Numeric ids first in numeric order, then the others by name.
bool id_less(const std::string& a, const std::string& b) {
  const bool na = is_numeric(a), nb = is_numeric(b);
  if (na != nb) return na;
  if (na) {
    const uint64_t ia = std::stoull(a), ib = std::stoull(b);
    if (ia != ib) return ia < ib;
  }
  return a < b;
}

Expected<std::map<std::string, UpAxis>> read_up_axes(const std::string& path) {
  std::ifstream in(path);
  if (!in) return not_found(path + ": cannot open");
  std::map<std::string, UpAxis> up;
  std::string line;
  for (size_t line_no = 1; std::getline(in, line); ++line_no) {
    std::string_view s = line;
    if (const size_t hash = s.find('#'); hash != std::string_view::npos) s = s.substr(0, hash);
    s = trim(s);
    if (s.empty()) continue;
    const size_t comma = s.find(',');
    const std::string where = path + ":" + std::to_string(line_no) + ": ";
    if (comma == std::string_view::npos || s.find(',', comma + 1) != std::string_view::npos)
      return invalid_argument(where + "expected 'id,up' such as '104,+z'");
    const std::string id(trim(s.substr(0, comma)));
    Expected<UpAxis> axis = parse_up_axis(s.substr(comma + 1));
    if (id.empty()) return invalid_argument(where + "empty id");
    if (!axis) return invalid_argument(where + axis.error().message);
    if (!up.emplace(id, *axis).second) return invalid_argument(where + "id '" + id + "' listed twice");
  }
  return up;
}

// SplitMix64 (Steele, Lea & Flood 2014): decorrelates the (seed, object) pair.
uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

uint64_t fnv1a(std::string_view s) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (char c : s) h = (h ^ static_cast<unsigned char>(c)) * 0x100000001b3ull;
  return h;
}

}  // namespace

std::vector<CategorySize> paper_category_sizes() {
  return {
      {"human", CategorySize::kHeight, 1.55f, 1.95f},
      {"chair", CategorySize::kHeight, 0.80f, 1.10f},
      {"table", CategorySize::kHeight, 0.70f, 0.80f},
      {"fourleg", CategorySize::kHeight, 0.50f, 2.00f},
      {"mechanic", CategorySize::kLargestExtent, 0.10f, 0.40f},
  };
}

CategorySize category_size(std::string_view category, const std::vector<CategorySize>& table) {
  for (const CategorySize& s : table)
    if (s.category == category) return s;
  return CategorySize{std::string(category), CategorySize::kLargestExtent, 0.3f, 1.0f};
}

Expected<Dataset> scan_dataset(const std::string& dir, const std::vector<CategorySize>& sizes) {
  try {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return not_found(dir + ": no such dataset folder");
    std::map<std::string, UpAxis> up;
    const fs::path csv = fs::path(dir) / "up_axis.csv";
    if (fs::exists(csv, ec)) {
      Expected<std::map<std::string, UpAxis>> read = read_up_axes(csv.string());
      if (!read) return read.error();
      up = std::move(*read);
    }
    Dataset ds;
    ds.root = dir;
    for (const fs::directory_entry& folder : fs::directory_iterator(dir)) {
      const std::string category = folder.path().filename().string();
      if (!folder.is_directory() || category.empty() || category.front() == '.') continue;
      bool any = false;
      for (const fs::directory_entry& file : fs::directory_iterator(folder.path())) {
        if (!file.is_regular_file() || !is_mesh_file(file.path())) continue;
        DatasetObject o;
        o.category = category;
        o.id = file.path().stem().string();
        o.path = file.path().string();
        if (const auto it = up.find(o.id); it != up.end()) o.up = it->second;
        o.size = category_size(category, sizes);
        ds.objects.push_back(std::move(o));
        any = true;
      }
      if (any) ds.categories.push_back(category);
    }
    if (ds.objects.empty())
      return not_found(dir + ": no <category>/<id>.(off|obj|ply) meshes in this dataset folder");
    std::sort(ds.categories.begin(), ds.categories.end());
    std::sort(ds.objects.begin(), ds.objects.end(), [](const DatasetObject& a, const DatasetObject& b) {
      if (a.category != b.category) return a.category < b.category;
      if (a.id != b.id) return id_less(a.id, b.id);
      return a.path < b.path;  // same id in two formats
    });
    return ds;
  } catch (const fs::filesystem_error& e) {
    return not_found(dir + ": " + e.what());
  } catch (const std::bad_alloc&) {
    return resource_exhausted(dir + ": out of memory while scanning");
  } catch (const std::exception& e) {
    return internal_error(dir + ": " + e.what());
  }
}

float object_size_m(const DatasetObject& object, uint64_t seed) {
  std::mt19937_64 rng(splitmix64(seed ^ fnv1a(object.category + "/" + object.id)));
  const double u = double(rng() >> 11) * 0x1.0p-53;  // uniform [0, 1), library-independent
  return float(object.size.min_m + u * (object.size.max_m - object.size.min_m));
}

Expected<Mesh> load_object(const DatasetObject& object, uint64_t seed) {
  Expected<Mesh> mesh = read_mesh(object.path);
  if (!mesh) return mesh.error();
  if (mesh->vertices.empty()) return invalid_argument(object.path + ": mesh has no vertices");
  for (const Vec3& v : mesh->vertices)
    if (!v.allFinite()) return invalid_argument(object.path + ": mesh has non-finite vertices");
  Mesh m = stand_upright(std::move(*mesh), object.up);
  const float size = object_size_m(object, seed);
  m = object.size.measure == CategorySize::kHeight ? scale_to_height(std::move(m), size)
                                                   : scale_to_largest_extent(std::move(m), size);
  return place_on_ground(std::move(m));
}

}  // namespace glimpse

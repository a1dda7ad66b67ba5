// Dataset manifests (DIR/<category>/<file>, up_axis.csv, sizes.csv) and loading objects upright at
// real-life size (sec. 3.4).
#include "glimpse/views/dataset.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <cmath>
#include <cstdlib>
#include <map>
#include <new>
#include <random>
#include <set>

#include "glimpse/io/files.h"
#include "glimpse/random.h"
#include "glimpse/views/placement.h"

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
  return ext == ".off" || ext == ".obj" || ext == ".ply" || ext == ".stl";
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

// One manifest row: "key,rest" split at the first comma, comments and blanks removed; false for a
// blank line.
struct Row {
  std::string key;
  std::string_view rest;
};

// Calls parse(row, where) for every data row; stops at its first error.
template <class Parse>
Status read_rows(const std::string& path, Parse&& parse) {
  std::ifstream in(path);
  if (!in) return not_found(path + ": cannot open");
  std::string line;
  for (size_t line_no = 1; std::getline(in, line); ++line_no) {
    std::string_view s = line;
    if (const size_t hash = s.find('#'); hash != std::string_view::npos) s = s.substr(0, hash);
    s = trim(s);
    if (s.empty()) continue;
    const std::string where = path + ":" + std::to_string(line_no) + ": ";
    if (Status st = parse(s, where); !st.ok()) return st;
  }
  return {};
}

std::vector<std::string_view> split_commas(std::string_view s) {
  std::vector<std::string_view> out;
  for (size_t start = 0;;) {
    const size_t comma = s.find(',', start);
    out.push_back(trim(s.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) return out;
    start = comma + 1;
  }
}

Expected<std::map<std::string, Vec3>> read_up_axes(const std::string& path) {
  std::map<std::string, Vec3> up;
  Status st = read_rows(path, [&](std::string_view s, const std::string& where) -> Status {
    const std::vector<std::string_view> cols = split_commas(s);
    if (cols.size() != 2) return invalid_argument(where + "expected 'id,up' or 'category/file,up' such as '104,+z'");
    const std::string key(cols[0]);
    if (key.empty()) return invalid_argument(where + "empty id");
    Expected<Vec3> dir = parse_up(cols[1]);
    if (!dir) return invalid_argument(where + dir.error().message);
    if (!up.emplace(key, *dir).second) return invalid_argument(where + "'" + key + "' listed twice");
    return {};
  });
  if (!st.ok()) return st.error();
  return up;
}

bool parse_metres(std::string_view t, float& out) {
  const std::string text(t);
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end || !std::isfinite(v) || !(v > 0) || v > 1e4) return false;
  out = static_cast<float>(v);
  return true;
}

}  // namespace

Expected<std::vector<CategorySize>> read_category_sizes(const std::string& path) {
  std::vector<CategorySize> sizes;
  Status st = read_rows(path, [&](std::string_view s, const std::string& where) -> Status {
    const std::vector<std::string_view> cols = split_commas(s);
    if (cols.size() != 4 && cols.size() != 5)
      return invalid_argument(where + "expected 'category,height|extent,min_m,max_m[,upright|any-pose]'");
    CategorySize c;
    c.category = std::string(cols[0]);
    if (c.category.empty()) return invalid_argument(where + "empty category");
    const std::string measure = lower(std::string(cols[1]));
    if (measure == "height") c.measure = CategorySize::kHeight;
    else if (measure == "extent") c.measure = CategorySize::kLargestExtent;
    else return invalid_argument(where + "measure must be 'height' or 'extent', not '" + std::string(cols[1]) + "'");
    if (!parse_metres(cols[2], c.min_m) || !parse_metres(cols[3], c.max_m) || c.min_m > c.max_m)
      return invalid_argument(where + "sizes must be metres with 0 < min_m <= max_m");
    if (cols.size() == 5) {
      const std::string pose = lower(std::string(cols[4]));
      if (pose == "any-pose") c.any_pose = true;
      else if (pose != "upright") return invalid_argument(where + "pose must be 'upright' or 'any-pose', not '" + pose + "'");
    }
    for (const CategorySize& other : sizes)
      if (other.category == c.category) return invalid_argument(where + "category '" + c.category + "' listed twice");
    sizes.push_back(std::move(c));
    return {};
  });
  if (!st.ok()) return st.error();
  return sizes;
}

namespace {

uint64_t fnv1a(std::string_view s) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (char c : s) h = (h ^ static_cast<unsigned char>(c)) * 0x100000001b3ull;
  return h;
}

}  // namespace

std::vector<CategorySize> default_category_sizes() {
  return {
      {"human", CategorySize::kHeight, 1.55f, 1.95f, false},
      {"chair", CategorySize::kHeight, 0.80f, 1.10f, false},
      {"table", CategorySize::kHeight, 0.70f, 0.80f, false},
      {"fourleg", CategorySize::kHeight, 0.50f, 2.00f, false},
      {"mechanic", CategorySize::kLargestExtent, 0.10f, 0.40f, true},
  };
}

CategorySize category_size(std::string_view category, const std::vector<CategorySize>& table) {
  for (const CategorySize& s : table)
    if (s.category == category) return s;
  return CategorySize{std::string(category), CategorySize::kLargestExtent, 0.3f, 1.0f, false};
}

Expected<Dataset> scan_dataset(const std::string& dir, const std::vector<CategorySize>& defaults) {
  try {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return not_found(dir + ": no such dataset folder");
    Dataset ds;
    ds.root = dir;
    std::map<std::string, Vec3> up;
    if (const fs::path csv = fs::path(dir) / "up_axis.csv"; fs::exists(csv, ec)) {
      Expected<std::map<std::string, Vec3>> read = read_up_axes(csv.string());
      if (!read) return read.error();
      up = std::move(*read);
      ds.has_up_axes = true;
    }
    std::vector<CategorySize> sizes = defaults;
    if (const fs::path csv = fs::path(dir) / "sizes.csv"; fs::exists(csv, ec)) {
      Expected<std::vector<CategorySize>> read = read_category_sizes(csv.string());
      if (!read) return read.error();
      for (CategorySize& c : *read) {  // the folder's rows replace the defaults of their categories
        std::erase_if(sizes, [&](const CategorySize& d) { return d.category == c.category; });
        sizes.push_back(std::move(c));
      }
      ds.has_sizes = true;
    }
    std::set<std::string> matched;
    for (const fs::directory_entry& folder : fs::directory_iterator(dir)) {
      const std::string category = folder.path().filename().string();
      if (!folder.is_directory() || category.empty() || category.front() == '.') continue;
      bool any = false;
      for (const fs::directory_entry& file : fs::directory_iterator(folder.path())) {
        // Hidden files are not objects (macOS's "._x.off" beside x.off is not a mesh at all).
        if (!file.is_regular_file() || !is_mesh_file(file.path()) || file.path().filename().string().front() == '.')
          continue;
        DatasetObject o;
        o.category = category;
        o.id = file.path().stem().string();
        o.path = file.path().string();
        // The most specific key wins: category/file.ext, category/file, then the bare id.
        for (const std::string& key : {category + "/" + file.path().filename().string(), category + "/" + o.id, o.id})
          if (const auto it = up.find(key); it != up.end()) {
            o.up = it->second;
            matched.insert(key);
            break;
          }
        o.size = category_size(category, sizes);
        ds.objects.push_back(std::move(o));
        any = true;
      }
      if (any) ds.categories.push_back(category);
    }
    if (ds.objects.empty())
      return not_found(dir + ": no <category>/<file>.(off|obj|ply|stl) meshes in this dataset folder");
    ds.unmatched_up_rows = up.size() - matched.size();
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

Expected<Mesh> load_object(const DatasetObject& object, uint64_t seed, const Sizing& sizing) {
  Expected<Mesh> mesh = read_mesh(object.path);
  if (!mesh) return mesh.error();
  if (mesh->vertices.empty()) return invalid_argument(object.path + ": mesh has no vertices");
  // Views are cut from a mesh's surface; a file of vertices alone is a point cloud, which cutting would
  // silently re-cut into views of views.
  if (mesh->faces.empty())
    return invalid_argument(object.path + ": no faces: a point cloud, not a mesh (an object is cut into views " +
                            "from its surface; a cloud to learn as it is goes in a .pcd or .xyz file)");
  for (const Vec3& v : mesh->vertices)
    if (!v.allFinite()) return invalid_argument(object.path + ": mesh has non-finite vertices");
  Mesh m = stand_upright(std::move(*mesh), object.up);
  switch (sizing.kind) {
    case Sizing::kCategoryRange: {
      const float size = object_size_m(object, seed);
      m = object.size.measure == CategorySize::kHeight ? scale_to_height(std::move(m), size)
                                                       : scale_to_largest_extent(std::move(m), size);
      break;
    }
    case Sizing::kUnit: m = scale_uniform(std::move(m), sizing.value); break;
    case Sizing::kHeight: m = scale_to_height(std::move(m), sizing.value); break;
  }
  return place_on_ground(std::move(m));
}

}  // namespace glimpse

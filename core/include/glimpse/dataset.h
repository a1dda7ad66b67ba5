// A manifest of a mesh dataset laid out as DIR/<category>/<id>.(off|obj|ply), e.g. the five SHREC 2007
// categories of the paper (sec. 3.4), and loading one object upright at a real-life size.
//
// DIR/up_axis.csv (optional): '#' comment lines, then "id,up" rows such as "104,+z": the model axis
// that points up in the world. Models not listed stand along +y. Rows for ids not in the dataset are
// ignored; a malformed row or a repeated id is an error naming the file and line.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/views.h"

namespace glimpse {

// The real-life size range of a category; each object gets a size drawn uniformly in it, so one
// fixed size per category does not give the class away.
struct CategorySize {
  enum Measure { kHeight, kLargestExtent };
  std::string category;
  Measure measure = kLargestExtent;
  float min_m = 0.3f;
  float max_m = 1.0f;
};

// Sec. 3.4 ("resized the objects to real life measure"), the ranges are our spec: human height
// 1.55-1.95 m, chair 0.80-1.10, table 0.70-0.80, fourleg (quadruped) height 0.50-2.00, mechanic
// (machine part) largest extent 0.10-0.40.
std::vector<CategorySize> paper_category_sizes();

// The entry for `category` in `table`; a category not in it gets largest extent 0.3-1.0 m.
CategorySize category_size(std::string_view category,
                           const std::vector<CategorySize>& table = paper_category_sizes());

struct DatasetObject {
  std::string category;  // folder name
  std::string id;        // file stem, e.g. "104"
  std::string path;
  UpAxis up = UpAxis::kPosY;
  CategorySize size;  // from the table given to scan_dataset; may be edited before load_object
};

struct Dataset {
  std::string root;
  std::vector<std::string> categories;  // sorted; folders holding at least one mesh
  std::vector<DatasetObject> objects;   // by category, then numeric id (non-numeric ids after, by name)
};

// Lists the dataset (no mesh is read). Hidden folders and files of other extensions are skipped.
// Errors: the folder is missing (kNotFound) or holds no meshes, a bad up_axis.csv row.
Expected<Dataset> scan_dataset(const std::string& dir,
                               const std::vector<CategorySize>& sizes = paper_category_sizes());

// The size (metres, in the object's measure) load_object gives this object: uniform in its range,
// seeded by (seed, category, id), so it is the same on every call and every machine.
float object_size_m(const DatasetObject& object, uint64_t seed);

// Reads the mesh, stands it upright (object.up -> +z), scales it to object_size_m (height or
// largest extent) and puts it on the ground (min z = 0) centred in x, y.
Expected<Mesh> load_object(const DatasetObject& object, uint64_t seed);

}  // namespace glimpse

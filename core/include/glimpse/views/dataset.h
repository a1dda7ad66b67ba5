// A labelled mesh folder laid out as DIR/<category>/<file>.(off|obj|ply|stl) — the five SHREC 2007
// categories of the paper (sec. 3.4), the Princeton Shape Benchmark, a user's own — with its manifest,
// and loading one object upright at its real-life size. The lab, the client and the tests all read
// datasets through this one loader.
//
// Manifest (both files optional, '#' starts a comment, a malformed or repeated row is an error naming
// the file and line):
//   DIR/up_axis.csv  "key,up": key is a file stem ("104", any category) or "category/file" (with or
//                    without the extension); up is a signed axis ("+z") or a vector "x y z" in the
//                    mesh's own coordinates. Files not listed stand along +y. Rows that match no file
//                    are ignored (counted in Dataset::unmatched_up_rows).
//   DIR/sizes.csv    "category,height|extent,min_m,max_m[,upright|any-pose]": the real-life size range
//                    of a category (its height along up, or its largest bounding-box extent) and
//                    whether it has a natural up. Categories not listed take default_category_sizes().
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse {

// The real-life size range of a category; each object gets a size drawn uniformly in it, so one
// fixed size per category does not give the class away.
struct CategorySize {
  enum Measure { kHeight, kLargestExtent };
  std::string category;
  Measure measure = kLargestExtent;
  float min_m = 0.3f;
  float max_m = 1.0f;
  // No natural up (machine parts): found lying in any pose, so its views are taken in random poses.
  bool any_pose = false;
};

// Sec. 3.4 ("resized the objects to real life measure"), the ranges are our spec: human height
// 1.55-1.95 m, chair 0.80-1.10, table 0.70-0.80, fourleg (quadruped) height 0.50-2.00, mechanic
// (machine part) largest extent 0.10-0.40 and any pose.
std::vector<CategorySize> default_category_sizes();

// The entry for `category` in `table`; a category not in it gets largest extent 0.3-1.0 m, upright.
CategorySize category_size(std::string_view category,
                           const std::vector<CategorySize>& table = default_category_sizes());

// How load_object sizes an object.
struct Sizing {
  enum Kind {
    kCategoryRange,  // a size drawn in the category's range (meshes in arbitrary units: SHREC, PSB)
    kUnit,           // the mesh's units times `value` metres (1 for metres, 0.01 for centimetres)
    kHeight,         // every object `value` metres tall (the size-blind ablation; a user's --height)
  };
  Kind kind = kCategoryRange;
  float value = 1;
};

struct DatasetObject {
  std::string category;  // folder name
  std::string id;        // file stem, e.g. "104"
  std::string path;
  Vec3 up = Vec3::UnitY();  // in the mesh's own coordinates
  CategorySize size;        // from sizes.csv or the defaults; may be edited before load_object
};

struct Dataset {
  std::string root;
  std::vector<std::string> categories;  // sorted; folders holding at least one mesh
  std::vector<DatasetObject> objects;   // by category, then numeric id (non-numeric ids after, by name)
  bool has_up_axes = false;             // DIR/up_axis.csv was read
  bool has_sizes = false;               // DIR/sizes.csv was read
  size_t unmatched_up_rows = 0;
};

// Lists the dataset and reads its manifest (no mesh is read). Hidden folders and files of other
// extensions are skipped. Errors: the folder is missing (kNotFound) or holds no meshes, a bad row.
// `defaults` size the categories sizes.csv does not list.
Expected<Dataset> scan_dataset(const std::string& dir,
                               const std::vector<CategorySize>& defaults = default_category_sizes());

// The parsers behind scan_dataset, for files elsewhere.
Expected<std::vector<CategorySize>> read_category_sizes(const std::string& path);

// The size (metres, in the object's measure) a category-range load gives this object: uniform in its
// range, seeded by (seed, category, id), so it is the same on every call and every machine.
float object_size_m(const DatasetObject& object, uint64_t seed);

// Reads the mesh, stands it upright (object.up -> +z), sizes it (see Sizing) and puts it on the
// ground (min z = 0) centred in x, y.
Expected<Mesh> load_object(const DatasetObject& object, uint64_t seed, const Sizing& sizing = {});

}  // namespace glimpse

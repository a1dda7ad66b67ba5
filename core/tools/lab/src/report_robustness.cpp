// The report's sections on a sensor's test views and on the robustness matrix: closest and right and
// accepted under each condition, and accuracy against the points a view keeps.
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "report_format.h"
#include "protocol.h"

namespace glimpse::eval_internal {

namespace {

// The values of the main stages (keypoint stages have none), as "a / b / c".
std::string stage_cells(const EvalResult& r, const std::vector<double>& v, const std::vector<double>* base = nullptr) {
  std::string o;
  for (size_t s = 0; s < r.params.stages.size() && s < v.size(); ++s) {
    if (r.params.stages[s].kind == StageKind::kKeypoints) continue;
    if (!o.empty()) o += " / ";
    if (!base) {
      o += pct(v[s], 1);
      continue;
    }
    const double d = v[s] - (*base)[s];
    o.append(d >= 0 ? "+" : "").append(pct(d, 1));
  }
  return o;
}

std::string matrix_table(const EvalResult& r) {
  std::string stages;
  for (const Stage& s : r.params.stages)
    if (s.kind != StageKind::kKeypoints) stages += (stages.empty() ? "" : " / ") + stage_name(s);
  bool unknowns = false;
  for (const RobustnessRow& row : r.robustness) unknowns = unknowns || !std::isnan(row.unknown_accepted);
  std::string o = "| condition | points raw | points kept | ground removed | closest " + stages + " | delta | right and accepted " +
                  stages + " | delta |" + (unknowns ? " unknown accepted |" : "") + " balanced | no decision | seconds |\n" +
                  "|---|---:|---:|---:|---:|---:|---:|---:|" + (unknowns ? "---:|" : "") + "---:|---:|---:|\n";
  const RobustnessRow& base = r.robustness.front();
  for (const RobustnessRow& row : r.robustness) {
    const bool first = &row == &base;
    o += "| " + describe(row.condition) + " | " + std::to_string(std::llround(row.median_points_raw)) + " | " +
         std::to_string(std::llround(row.median_points)) + " | " + std::to_string(row.ground_views) + " | " +
         stage_cells(r, row.accuracy) + " | " + (first ? "–" : stage_cells(r, row.accuracy, &base.accuracy)) + " | " +
         stage_cells(r, row.accepted) + " | " + (first ? "–" : stage_cells(r, row.accepted, &base.accepted)) + " |" +
         (unknowns ? std::string(" ").append(pct(row.unknown_accepted, 1)).append(" |") : std::string()) + " " +
         pct(row.balanced.empty() ? NAN : row.balanced.front(), 1) + " | " + std::to_string(row.failed) + " | " +
         pct(row.seconds, 1) + " |\n";
  }
  return o;
}

// Full views of every sensor row (the ideal rows apart) by the points the filters kept: closest and
// right and accepted, per sensor.
std::string points_table(const EvalResult& r) {
  constexpr std::array<size_t, 8> kEdges = {0, 50, 100, 200, 300, 500, 1000, 2000};
  struct Bin {
    size_t views = 0, right = 0, accepted = 0;
  };
  std::array<std::array<Bin, kEdges.size()>, 2> bins{};  // [depth camera, LiDAR][bin]
  bool any = false;
  for (const RobustnessRow& row : r.robustness) {
    if (row.condition.sensor == SensorKind::kIdeal) continue;
    const size_t k = row.condition.sensor == SensorKind::kLidar;
    for (const RobustnessRow::ViewOutcome& v : row.full_views) {
      size_t b = kEdges.size() - 1;
      while (b > 0 && v.points < kEdges[b]) --b;
      Bin& bin = bins[k][b];
      ++bin.views, bin.right += v.right, bin.accepted += v.accepted;
      any = true;
    }
  }
  if (!any) return "";
  std::string o = "Full views of every sensor condition above by the points the filters kept (the view's object "
                  "alone): closest / right and accepted, % (views).\n\n| points kept | depth camera | LiDAR |\n|---|---:|---:|\n";
  for (size_t b = 0; b < kEdges.size(); ++b) {
    if (!bins[0][b].views && !bins[1][b].views) continue;
    o += "| " + (b + 1 < kEdges.size() ? std::to_string(kEdges[b]) + "-" + std::to_string(kEdges[b + 1] - 1)
                                       : std::to_string(kEdges[b]) + " and more") + " |";
    for (const Bin& bin : {bins[0][b], bins[1][b]}) {
      if (!bin.views) {
        o += " – |";
        continue;
      }
      const double n = double(bin.views);
      o.append(" ").append(pct(100.0 * double(bin.right) / n, 1)).append(" / ");
      o.append(pct(100.0 * double(bin.accepted) / n, 1)).append(" (").append(std::to_string(bin.views)).append(") |");
    }
    o += "\n";
  }
  return o + "\n";
}

}  // namespace

std::string robustness_section(const EvalResult& r) {
  std::string o;
  const ScanCondition& test = r.params.test_condition;
  if (!test.is_ideal())
    o += "## Test views from a simulated sensor\n\nEvery tested view above was taken as **" + describe(test) +
         "** (rays cast against the mesh, Embree), then filtered (ground plane, isolated points, voxel grid to the "
         "training views' density). Stage fractions are the same share of the sensor view's points as of the ideal "
         "view's.\n\n";
  if (r.robustness.empty()) return o;
  o += "## Robustness matrix: real sensors and scene residue\n\n";
  o += "The models above (" + std::string(method_name(r.change_method)) + ") classify " +
       std::to_string(r.robustness.front().views) + " tested views (" + std::to_string(r.params.matrix_views_per_object) +
       " per object) taken under each condition, after the filters every scan goes through: RANSAC ground plane, "
       "isolated points, voxel grid down to the training views' density (median relative density ";
  for (size_t i = 0; i < r.trained_density.size(); ++i) o += (i ? ", " : "") + pct(r.trained_density[i], 1);
  o += " points per extent^2). Depth camera: 640x480, 57x43 deg, 0.5-4.5 m, sigma(z) = 1.2 mm + 1.9 mm (z - 0.4)^2, "
       "1/8 px disparity steps, returns thinning beyond 70 deg incidence; it aims at the object's centre, so a large "
       "object near it is cut by the field of view; below 0 degrees it looks up from under the object's centre. LiDAR: "
       "16 beams over +-15 deg, 32 over -25..15 deg, 64 over -24.9..2 deg, 0.2 deg steps, 1.5 cm range noise. Closest: "
       "the closest category right; right and accepted: right and not called unknown at the model's own operating "
       "point. Delta: points against the first (ideal) row.\n\n";
  o += matrix_table(r);
  o += "\nPoints are medians per view (full view). \"no decision\": full views left with too few points to decide "
       "(counted as wrong).\n\n";
  return o + points_table(r);
}

}  // namespace glimpse::eval_internal

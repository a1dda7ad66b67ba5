// The evaluation's metrics and report writers on hand-made results: category changes, settling, the
// open set, the markdown, CSV and SVG writers and the report folder.
#include <gtest/gtest.h>

#include <set>

#include <cmath>
#include <filesystem>
#include <sstream>

#include "common/decisions.h"
#include "common/temp_dir.h"
#include "glimpse/lab/evaluation.h"
#include "glimpse/views/exploration.h"
#include "glimpse/views/sampling.h"

namespace glimpse {
namespace {

using testing::decision;

// ---- metrics ---------------------------------------------------------------------------------------

TEST(Metrics, CategoryChangesOnAScriptedSequence) {
  EXPECT_EQ(category_changes(std::vector<int>{}), 0u);
  EXPECT_EQ(category_changes(std::vector<int>{3}), 0u);
  EXPECT_EQ(category_changes(std::vector<int>{1, 1, 2, 2, 1, 3, 3}), 3u);
  EXPECT_EQ(category_changes(std::vector<int>{-1, 0, 0}), 1u);
}

TEST(Metrics, TracesAndChangeSummarySplitByFinalCorrectness) {
  const std::vector<size_t> grid = {1, 5, 10};
  std::vector<StageDecision> d;
  // View A (object 0, truth 0): 2, 0, 0 then full 0 -> correct, 1 change up to 10, 0 up to 1.
  for (auto [stage, w] : std::vector<std::pair<std::string, int>>{{"1kp", 2}, {"5kp", 0}, {"10kp", 0}, {"full", 0}})
    d.push_back(decision(stage, MethodId::kBoK, 0, w, 0));
  // View B (object 1, truth 1): 0, 1, 0 then full 0 -> incorrect, 2 changes up to 10, 1 up to 5.
  for (auto [stage, w] : std::vector<std::pair<std::string, int>>{{"1kp", 0}, {"5kp", 1}, {"10kp", 0}, {"full", 0}})
    d.push_back(decision(stage, MethodId::kBoK, 1, w, 1));
  d.push_back(decision("1kp", MethodId::kVFH, 1, 0, 1));  // another method: ignored
  d.push_back(decision("5kp", MethodId::kBoK, 1, 1, 2));  // no full-view decision: skipped

  const std::vector<ExplorationTrace> traces = exploration_traces(d, MethodId::kBoK, grid);
  ASSERT_EQ(traces.size(), 2u);
  EXPECT_TRUE(traces[0].correct());
  EXPECT_FALSE(traces[1].correct());
  EXPECT_EQ(traces[1].winners, (std::vector<int>{0, 1, 0}));

  const std::vector<ChangeRow> rows = change_summary(traces, {1, 5, 10});
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_DOUBLE_EQ(rows[0].mean_correct, 0.0);
  EXPECT_DOUBLE_EQ(rows[1].mean_correct, 1.0);
  EXPECT_DOUBLE_EQ(rows[1].mean_incorrect, 1.0);
  EXPECT_DOUBLE_EQ(rows[2].mean_correct, 1.0);
  EXPECT_DOUBLE_EQ(rows[2].mean_incorrect, 2.0);
  EXPECT_EQ(rows[2].views_correct, 1u);
  EXPECT_EQ(rows[2].views_incorrect, 1u);
}

// ---- writers ---------------------------------------------------------------------------------------

size_t occurrences(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + what.size())) ++n;
  return n;
}

// A hand-made result: two categories, one method, three stages.
EvalResult small_result() {
  EvalResult r;
  r.params.methods = {MethodId::kBoK};
  r.params.stages = {{StageKind::kFull, 0}, {StageKind::kKeypoints, 10}, {StageKind::kFraction, 0.1}};
  r.params.folds = 2;
  r.source = "hand-made";
  r.categories = {"human", "chair"};
  r.object_ids = {"human/1", "chair/2"};
  r.object_truth = {0, 1};
  r.object_fold = {0, 1};
  r.object_points = {1000, 1200};
  r.grid = {1, 5, 10};
  r.change_method = MethodId::kBoK;
  for (const char* stage : {"full", "10kp", "10%", "1kp", "5kp"}) {
    StageDecision a = decision(stage, MethodId::kBoK, 0, 0, 0, 0.25);
    a.scores = {0.75, 0.25};
    StageDecision b = decision(stage, MethodId::kBoK, 1, std::string(stage) == "full" ? 0 : 1, 1, 0.375);
    b.scores = {0.5, 0.5};
    r.decisions.push_back(a);
    r.decisions.push_back(b);
  }
  StageStats st;
  st.stage = "full";
  st.keypoints = {12.5, 7.25};
  st.visible_percent = {25, 37.5};
  st.failed = {0, 0};
  st.mean_keypoints = 9.875;
  st.mean_visible_percent = 31.25;
  r.stage_stats.push_back(st);
  r.traces = exploration_traces(r.decisions, MethodId::kBoK, {1, 5, 10});
  r.changes = change_summary(r.traces, {10});
  r.timings.push_back({"features", 12.5, "2 clouds"});
  r.total_seconds = 13;
  r.notes.push_back("something odd");
  return r;
}

TEST(Writers, MarkdownContainsTheNumbersAndThePapers) {
  const EvalResult r = small_result();
  const std::string md = markdown_report(r);
  EXPECT_NE(md.find("# Glimpse evaluation"), std::string::npos);
  EXPECT_NE(md.find("| BoK | **50.0** (89) | **100.0** (64) | **100.0** (64) |"), std::string::npos) << md;
  EXPECT_NE(md.find("12.5"), std::string::npos);   // keypoints per category
  EXPECT_NE(md.find("37.5"), std::string::npos);   // visible % per category
  EXPECT_NE(md.find("0.41 / 0.46"), std::string::npos);  // the paper's change figures
  EXPECT_NE(md.find("something odd"), std::string::npos);
  EXPECT_NE(md.find("Confusion, stage full (paper Table 1)"), std::string::npos);
  EXPECT_NE(md.find("| Human | BoK | **100** | 0 | 88 |"), std::string::npos) << md;
  // Every table row has the same number of cells as its header.
  std::istringstream lines(md);
  size_t header_cells = 0;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("|", 0) != 0) {
      header_cells = 0;
      continue;
    }
    const size_t cells = occurrences(line, "|");
    if (header_cells == 0) header_cells = cells;
    EXPECT_EQ(cells, header_cells) << line;
  }
}

// The sensors matrix covers the poses real scanners take: the depth camera at 0.8-4 m from -10 to 60 degrees, LiDAR
// of 16, 32 and 64 beams at 5-20 m, after the ideal row.
TEST(Robustness, TheSensorsMatrixSpansTheRealScannersPoses) {
  const std::vector<ScanCondition> grid = robustness_conditions("sensors");
  ASSERT_EQ(grid.size(), 1u + 30u + 9u);
  EXPECT_TRUE(grid.front().is_ideal());
  std::set<float> distances, elevations;
  std::set<std::pair<int, float>> lidars;
  for (const ScanCondition& c : grid) {
    if (c.sensor == SensorKind::kDepthCamera) distances.insert(c.distance_m), elevations.insert(c.elevation_deg);
    if (c.sensor == SensorKind::kLidar) lidars.insert({c.beams, c.distance_m});
  }
  EXPECT_EQ(distances, (std::set<float>{0.8f, 1.f, 2.f, 3.f, 4.f}));
  EXPECT_EQ(elevations, (std::set<float>{-10.f, 0.f, 15.f, 30.f, 45.f, 60.f}));
  EXPECT_EQ(lidars.size(), 9u);
  EXPECT_TRUE(lidars.count({64, 20.f}) && lidars.count({16, 5.f}) && lidars.count({32, 10.f}));
  EXPECT_TRUE(robustness_conditions("nonsense").empty());
}

// The matrix's rows give closest beside right and accepted, and the points table bins every sensor row's
// full views by the points kept (the ideal rows apart).
TEST(Robustness, MatrixRowsAndAccuracyAgainstPointsKept) {
  EvalResult r = small_result();
  RobustnessRow ideal, lidar;
  lidar.condition.sensor = SensorKind::kLidar, lidar.condition.beams = 32, lidar.condition.distance_m = 10.f;
  lidar.condition.elevation_deg = 5.f;
  for (RobustnessRow* row : {&ideal, &lidar}) {
    row->views = 4;
    row->accuracy = {75, NAN, 50}, row->accepted = {50, NAN, 25}, row->balanced = {75, NAN, 50};
  }
  ideal.full_views = {{2000, true, true}, {1500, true, false}};  // not binned: the ideal row
  lidar.full_views = {{40, false, false}, {60, true, false}, {80, true, true}, {250, true, true}};
  lidar.unknown_accepted = 12.5;
  r.robustness = {ideal, lidar};
  const std::string md = markdown_report(r);
  EXPECT_NE(md.find("| closest full / 10% | delta | right and accepted full / 10% | delta | unknown accepted |"),
            std::string::npos) << md;
  EXPECT_NE(md.find("| LiDAR 32 beams 10 m, 5 deg | 0 | 0 | 0 | 75.0 / 50.0 | +0.0 / +0.0 | 50.0 / 25.0 | +0.0 / +0.0 | 12.5 |"),
            std::string::npos) << md;
  EXPECT_NE(md.find("| 0-49 | – | 0.0 / 0.0 (1) |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 50-99 | – | 100.0 / 50.0 (2) |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 200-299 | – | 100.0 / 100.0 (1) |"), std::string::npos) << md;
  EXPECT_EQ(md.find("| 1000-1999 |"), std::string::npos) << md;  // the ideal row's views are not binned
}

TEST(Writers, CsvHasOneRowPerDecision) {
  const EvalResult r = small_result();
  const std::string csv = decisions_csv(r);
  EXPECT_EQ(occurrences(csv, "\n"), r.decisions.size() + 1);
  EXPECT_EQ(csv.rfind("fold,object,view,stage,method,visible_fraction,points,keypoints,truth,winner,score_human,score_chair,"
                      "novelty,unknown,probability_human,probability_chair\n", 0), 0u);
  EXPECT_NE(csv.find("0,chair/2,0,full,bok,0.3750,0,0,chair,human,0.5000,0.5000,,0,,\n"), std::string::npos) << csv;
}

TEST(Writers, SvgIsWellFormedWithOneLinePerView) {
  const EvalResult r = small_result();
  for (bool correct : {true, false}) {
    const std::string svg = evolution_svg(r.traces, r.categories, correct, "title <&>");
    EXPECT_EQ(svg.rfind("<svg xmlns=\"http://www.w3.org/2000/svg\"", 0), 0u);
    EXPECT_EQ(svg.substr(svg.size() - 7), "</svg>\n");
    EXPECT_EQ(occurrences(svg, "<g>"), occurrences(svg, "</g>"));
    EXPECT_EQ(occurrences(svg, "<polyline"), 1u);  // one view of each kind
    EXPECT_EQ(occurrences(svg, "<polyline"), occurrences(svg, "</polyline>"));
    EXPECT_NE(svg.find("title &lt;&amp;&gt;"), std::string::npos);
    EXPECT_NE(svg.find(">human</text>"), std::string::npos);
    EXPECT_EQ(svg.find("<&>"), std::string::npos);
  }
}

TEST(Writers, WriteReportCreatesTheFiles) {
  const glimpse::testing::TempDir tmp("lab-report");
  const std::string dir = tmp.file("report");
  ASSERT_TRUE(write_report(small_result(), dir).ok());
  for (const char* f : {"report.md", "decisions.csv", "evolution_correct.svg", "evolution_incorrect.svg"})
    EXPECT_GT(std::filesystem::file_size(std::filesystem::path(dir) / f), 100u) << f;
}

// ---- streaming metrics -----------------------------------------------------------------------------

StreamTrace trace(int truth, std::vector<int> winners, std::vector<double> confidence, std::vector<uint8_t> settled) {
  StreamTrace t;
  t.truth = truth;
  for (size_t i = 0; i < winners.size(); ++i) t.visible_fraction.push_back(0.1 * double(i + 1));
  t.winners = std::move(winners);
  t.confidence = std::move(confidence);
  t.settled = std::move(settled);
  t.keypoints.assign(t.winners.size(), 0);
  return t;
}

TEST(SettleSummary, FirstSettledChunkCountsOnceOnAScriptedSet) {
  const std::vector<StreamTrace> traces = {
      trace(0, {-1, 1, 0, 0}, {0.0, 0.3, 0.6, 0.9}, {0, 0, 1, 1}),  // settles right at 30 %
      trace(1, {0, 0, 1, 1}, {0.2, 0.7, 0.8, 0.9}, {0, 1, 1, 1}),   // settles WRONG at 20 %
      trace(1, {1, 1, 1, 1}, {0.1, 0.2, 0.3, 0.4}, {0, 0, 0, 0}),   // never settles
  };
  const SettleRow own = settle_summary(traces, -1);
  EXPECT_EQ(own.views, 3u);
  EXPECT_EQ(own.settled_views, 2u);
  EXPECT_EQ(own.correct, 1u);
  EXPECT_NEAR(own.mean_visible_percent, 25.0, 1e-9);
  EXPECT_NEAR(own.precision_percent(), 50.0, 1e-9);
  // Recomputed from confidences: at 0.75 the first view settles right at 40 %, the second at 30 %.
  const SettleRow high = settle_summary(traces, 0.75);
  EXPECT_EQ(high.settled_views, 2u);
  EXPECT_EQ(high.correct, 2u);
  EXPECT_NEAR(high.mean_visible_percent, 35.0, 1e-9);
  // A threshold nothing reaches settles nothing; the category filter keeps one category's views.
  EXPECT_EQ(settle_summary(traces, 0.95).settled_views, 0u);
  EXPECT_EQ(settle_summary(traces, -1, 0, 1).views, 2u);
  // Keypoint requirement: with none recorded, min_keypoints 1 settles nothing.
  EXPECT_EQ(settle_summary(traces, 0.5, 1).settled_views, 0u);
}

TEST(SettleSummary, StreamsOfUnknownObjectsCountApartAndRightWhenTheySettleUnknown) {
  auto unknown_trace = [](int cls, std::vector<int> winners, std::vector<uint8_t> settled, std::vector<uint8_t> unknown) {
    StreamTrace t = trace(-1, std::move(winners), std::vector<double>(settled.size(), 0.6), std::move(settled));
    t.unknown_class = cls;
    t.unknown = std::move(unknown);
    return t;
  };
  std::vector<StreamTrace> traces = {
      trace(0, {0, 0}, {0.6, 0.9}, {0, 1}),                       // known, settles right at 20 %
      unknown_trace(0, {1, 1, 1}, {0, 1, 1}, {0, 1, 1}),          // settles "unknown" at 20 %: right
      unknown_trace(0, {1, 0, 0}, {0, 0, 1}, {1, 1, 0}),          // settles on category 0 at 30 %: wrong
      unknown_trace(1, {1, 1}, {0, 0}, {1, 1}),                   // never settles
  };
  traces[0].unknown = {1, 0};
  // The known view alone counts in the known metrics, whatever the unknown ones did.
  const SettleRow known = settle_summary(traces, -1);
  EXPECT_EQ(known.views, 1u);
  EXPECT_EQ(known.correct, 1u);
  EXPECT_EQ(known.unknown, 0u);
  const SettleRow unknown = unknown_settle_summary(traces);
  EXPECT_EQ(unknown.views, 3u);
  EXPECT_EQ(unknown.settled_views, 2u);
  EXPECT_EQ(unknown.correct, 1u);
  EXPECT_EQ(unknown.unknown, 1u);
  EXPECT_NEAR(unknown.mean_visible_percent, 25.0, 1e-9);
  EXPECT_EQ(unknown_settle_summary(traces, 1).views, 1u);
  EXPECT_EQ(unknown_settle_summary(traces, 1).settled_views, 0u);
  // A known view settled "unknown" counts wrong, and as unknown.
  traces[0].unknown = {1, 1};
  EXPECT_EQ(settle_summary(traces, -1).correct, 0u);
  EXPECT_EQ(settle_summary(traces, -1).unknown, 1u);
}

// ---- open set --------------------------------------------------------------------------------------

TEST(OpenSet, SummaryOnAHandMadeList) {
  auto make = [](int truth, int unknown_class, int winner, double novelty, bool unknown) {
    StageDecision d = decision("full", MethodId::kFusion, truth, winner);
    d.unknown_class = unknown_class;
    d.novelty = novelty;
    d.unknown = unknown;
    return d;
  };
  std::vector<StageDecision> ds;
  for (int i = 0; i < 20; ++i) ds.push_back(make(0, -1, i < 18 ? 0 : 1, 0.1 * i, i == 19));  // 18 right, 1 rejected
  ds.push_back(make(-1, 0, 0, 5.0, true));   // class 0: rejected
  ds.push_back(make(-1, 0, 1, 1.05, false));  // class 0: accepted, below the 95 % novelty of the known
  ds.push_back(make(-1, 1, -1, NAN, false)); // class 1: features failed, rejected for sure
  ds.push_back(make(0, -1, 0, 0.5, false));  // another method's decision is not counted
  ds.back().method = MethodId::kVFH;
  const std::vector<OpenSetRow> rows = open_set_summary(ds, {{StageKind::kFull, 0}}, MethodId::kFusion, 2);
  ASSERT_EQ(rows.size(), 1u);
  const OpenSetRow& r = rows[0];
  EXPECT_EQ(r.known, 20u);
  EXPECT_EQ(r.unknown, 3u);
  EXPECT_DOUBLE_EQ(r.known_acceptance, 95.0);
  EXPECT_NEAR(r.false_acceptance, 100.0 / 3, 1e-9);
  EXPECT_DOUBLE_EQ(r.known_accuracy_closed, 90.0);
  EXPECT_DOUBLE_EQ(r.known_accuracy_open, 90.0);  // the rejected known view was wrong anyway
  EXPECT_NEAR(r.accepted_accuracy, 100.0 * 18 / 19, 1e-9);
  EXPECT_NEAR(r.far_at_95, 100.0 / 3, 1e-9);  // 1.05 is below 1.8, the novelty accepting 19 of 20 known
  ASSERT_EQ(r.accepted_per_class.size(), 2u);
  EXPECT_DOUBLE_EQ(r.accepted_per_class[0], 50.0);
  EXPECT_DOUBLE_EQ(r.accepted_per_class[1], 0.0);
  // Known novelties 0, 0.1 .. 1.9 against 5, 1.05 and infinity: 1.05 beats 11 of the 20.
  EXPECT_NEAR(r.auroc, (20 + 11 + 20) / 60.0, 1e-9);
}

// ---- leave one source out -------------------------------------------------------------------------

TEST(LeaveOneSourceOut, ClosestBesideRightAndAcceptedPerSourceAndCategory) {
  EvalResult run;
  run.categories = {"chair", "table"};
  run.params.stages = {{StageKind::kFull, 0}};
  run.test_sources = {"psb"};
  run.train_sources = {"shrec07", "zoo"};
  auto& ds = run.decisions;
  // chair: objects 0-1, 4 views: 3 right, one of them called unknown. table: object 2, 2 views: 1 right.
  ds.push_back(decision("full", MethodId::kFusion, 0, 0, 0));
  ds.push_back(decision("full", MethodId::kFusion, 0, 0, 0));
  ds.push_back(decision("full", MethodId::kFusion, 0, 0, 1));
  ds.back().unknown = true;
  ds.push_back(decision("full", MethodId::kFusion, 0, 1, 1));
  ds.push_back(decision("full", MethodId::kFusion, 1, 1, 2));
  ds.push_back(decision("full", MethodId::kFusion, 1, 0, 2));
  ds.back().unknown = true;                                     // wrong and unknown: wrong both ways
  ds.push_back(decision("full", MethodId::kVFH, 1, 1, 2));     // another method: not counted
  ds.push_back(decision("full", MethodId::kFusion, -1, 0, 3));  // an unknown object: not a known view
  const std::vector<SourceRow> rows = leave_one_source_out_rows({run}, MethodId::kFusion);
  ASSERT_EQ(rows.size(), 3u);  // every category, then chair, then table
  EXPECT_EQ(rows[0].category, "");
  EXPECT_EQ(rows[0].views, 6u);
  EXPECT_EQ(rows[0].objects, 3u);
  EXPECT_EQ(rows[0].closest.correct, 4u);
  EXPECT_EQ(rows[0].accepted_right.correct, 3u);
  EXPECT_EQ(rows[0].rejected, 2u);
  EXPECT_EQ(rows[1].category, "chair");
  EXPECT_DOUBLE_EQ(rows[1].closest.percent(), 75.0);
  EXPECT_DOUBLE_EQ(rows[1].accepted_right.percent(), 50.0);
  EXPECT_LE(rows[1].accepted_interval.low, 50.0);
  EXPECT_GE(rows[1].accepted_interval.high, 50.0);
  EXPECT_EQ(rows[2].category, "table");
  EXPECT_DOUBLE_EQ(rows[2].closest.percent(), 50.0);
  EXPECT_DOUBLE_EQ(rows[2].accepted_right.percent(), 50.0);
  // One object: every resample is that object.
  EXPECT_DOUBLE_EQ(rows[2].closest_interval.low, 50.0);
  EXPECT_DOUBLE_EQ(rows[2].closest_interval.high, 50.0);
  std::string md = leave_one_source_out_report({run}, MethodId::kFusion);
  EXPECT_EQ(md.find("## Open set across sources"), std::string::npos);  // no unknown object tested
  run.unknown_categories = {"bed"};
  for (StageDecision& d : run.decisions) {
    d.novelty = d.truth < 0 ? 9.0 : 1.0;  // the unknown view more novel than every known one
    if (d.truth < 0) d.unknown_class = 0, d.unknown = true;
  }
  md = leave_one_source_out_report({run}, MethodId::kFusion);
  EXPECT_NE(md.find("| psb | full | 1.000 | 66.7 | 0.0 | 6 / 1 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| psb | shrec07, zoo | full | 3 | 6 | 66.7 ["), std::string::npos) << md;
  EXPECT_NE(md.find("| psb | chair | full | 2 | 75.0 ["), std::string::npos) << md;
}

TEST(Objects, CommonHeightMakesEveryObjectOneHeightOnTheGround) {
  for (const EvalObject& o : common_height(zoo_objects(1, 5), 1.0f)) {
    const Bounds b = bounds(o.mesh.vertices);
    EXPECT_NEAR(b.extent().z(), 1.0f, 1e-5f) << o.category;
    EXPECT_NEAR(b.min.z(), 0.0f, 1e-6f);
  }
}

}  // namespace
}  // namespace glimpse

// The evaluation protocol: folds, stage cuts, metrics, change counting, report writers, and reduced
// end-to-end runs on the zoo and (when present) on SHREC 2007.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include "common/decisions.h"
#include "glimpse/lab/evaluation.h"
#include "glimpse/geometry/scan_filters.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/hidden_point_removal.h"
#include "glimpse/views/exploration.h"

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

TEST(Writers, CsvHasOneRowPerDecision) {
  const EvalResult r = small_result();
  const std::string csv = decisions_csv(r);
  EXPECT_EQ(occurrences(csv, "\n"), r.decisions.size() + 1);
  EXPECT_EQ(csv.rfind("fold,object,view,stage,method,visible_fraction,points,keypoints,truth,winner,score_human,score_chair,"
                      "novelty,unknown\n", 0), 0u);
  EXPECT_NE(csv.find("0,chair/2,0,full,bok,0.3750,0,0,chair,human,0.5000,0.5000,,0\n"), std::string::npos) << csv;
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
  const std::string dir = (std::filesystem::temp_directory_path() / "glimpse_test_evaluation_report").string();
  std::filesystem::remove_all(dir);
  ASSERT_TRUE(write_report(small_result(), dir).ok());
  for (const char* f : {"report.md", "decisions.csv", "evolution_correct.svg", "evolution_incorrect.svg"})
    EXPECT_GT(std::filesystem::file_size(std::filesystem::path(dir) / f), 100u) << f;
  std::filesystem::remove_all(dir);
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

// ---- end to end ------------------------------------------------------------------------------------

TEST(RunEvaluation, RejectsBadInput) {
  EXPECT_FALSE(run_evaluation({}, {}, "none").ok());
  EvalParams one_fold;
  one_fold.folds = 1;
  EXPECT_FALSE(run_evaluation(zoo_objects(1, 1), one_fold, "zoo").ok());
}

EvalParams reduced_params() {
  EvalParams p;
  p.points_per_object = 3000;
  p.views_per_object = 3;
  p.folds = 2;
  p.methods = {MethodId::kBoK, MethodId::kVFH, MethodId::kFusion};
  p.explore_step = 25;
  p.seed = 7;
  return p;
}

TEST(RunEvaluation, ReducedProtocolOnTheZooIsWellAboveChance) {
  const std::vector<EvalObject> objects = zoo_objects(4, 3);
  const EvalParams p = reduced_params();
  auto r = run_evaluation(objects, p, "zoo");
  ASSERT_TRUE(r.ok()) << r.error().message;
  // Every (test view, stage, method) decided exactly once: each object is tested in exactly one fold.
  const size_t stages = p.stages.size() + 2;  // + exploration grid 1kp and 50kp (10, 25, 55 are main stages)
  EXPECT_EQ(r->decisions.size(), objects.size() * p.views_per_object * stages * p.methods.size());
  std::map<int, std::set<int>> folds_of_object;
  for (const StageDecision& d : r->decisions) {
    folds_of_object[d.object].insert(d.fold);
    EXPECT_EQ(d.fold, r->object_fold[d.object]);
  }
  for (const auto& [o, f] : folds_of_object) EXPECT_EQ(f.size(), 1u) << "object " << o;
  // Fraction stages hold their fraction of the full cloud (unless the view is smaller).
  for (const StageDecision& d : r->decisions) {
    if (d.stage == "10%") {
      EXPECT_NEAR(d.visible_fraction, 0.10, 1e-3);
    }
  }
  // Chance is 20 %. Measured (zoo 4 per category, seed 3, 2 folds, 3 views, 3000 points; parts in random
  // poses, training views tilted up to 5 degrees, fusion of USH and VFH, VFH over the surfaces' normals):
  // full view fusion 95.0 %, VFH 55.0 %, 20 % visible fusion 93.3 % (83.3 / 83.3 before the fusion's
  // logistic decision was the default); streams: 71.7 % settle, at 11.7 % visible on average, all right.
  // 60 test views: one view is 1.7 points.
  EXPECT_GE(accuracy(r->decisions, "full", MethodId::kFusion).percent(), 93.0);  // measured 95.0
  EXPECT_GE(accuracy(r->decisions, "20%", MethodId::kFusion).percent(), 91.0);   // measured 93.3
  EXPECT_GE(accuracy(r->decisions, "full", MethodId::kVFH).percent(), 51.0);     // measured 55.0
  EXPECT_FALSE(markdown_report(*r).empty());
  // Every test view streamed once, top to bottom, one entry per chunk, visible fraction growing.
  ASSERT_EQ(r->streams.size(), objects.size() * p.views_per_object);
  for (const StreamTrace& t : r->streams) {
    ASSERT_FALSE(t.winners.empty());
    ASSERT_EQ(t.confidence.size(), t.winners.size());
    EXPECT_TRUE(std::is_sorted(t.visible_fraction.begin(), t.visible_fraction.end()));
  }
  const SettleRow settled = settle_summary(r->streams, -1);
  // A view settled as "unknown" counts wrong (issue 20: the default operating point accepts 95 % of
  // held-out known clouds); before unknown could settle, 100 % of 40. Since "unknown" needs the newest
  // chunk's own novelty too: 39 of 39 settled views right (was 39 of 40 settled, 97.5 % right).
  // Since settling is cautious both ways (stop 42: "unknown" after 6 chunks at confidence 1, a category
  // at novelty <= 0.8 x the threshold): 43 of the 60 views settled, all right.
  EXPECT_GE(settled.precision_percent(), 97.0);  // measured 100 (43 of the 60 views settled; 44 before the cautious settling, 43 before novelty added its evidences, 39 before the logistic decision)
  EXPECT_GE(settled.settled_percent(), 70.0);    // measured 71.7 (73.3, 71.7, 65.0)
  std::cout << "zoo reduced: full fusion " << accuracy(r->decisions, "full", MethodId::kFusion).percent() << " %, VFH "
            << accuracy(r->decisions, "full", MethodId::kVFH).percent() << " %, 20 % fusion "
            << accuracy(r->decisions, "20%", MethodId::kFusion).percent() << " %; streams settled "
            << settled.settled_percent() << " % at " << settled.mean_visible_percent << " % visible, precision "
            << settled.precision_percent() << " %\n";

  // Deterministic whatever the thread count.
  EvalParams one = p;
  one.threads = 1;
  auto r1 = run_evaluation(objects, one, "zoo");
  ASSERT_TRUE(r1.ok());
  ASSERT_EQ(r1->decisions.size(), r->decisions.size());
  for (size_t i = 0; i < r->decisions.size(); ++i) {
    EXPECT_EQ(r1->decisions[i].winner, r->decisions[i].winner) << i;
    EXPECT_EQ(r1->decisions[i].scores, r->decisions[i].scores) << i;
  }
  ASSERT_EQ(r1->streams.size(), r->streams.size());
  for (size_t i = 0; i < r->streams.size(); ++i) {
    EXPECT_EQ(r1->streams[i].winners, r->streams[i].winners) << i;
    EXPECT_EQ(r1->streams[i].confidence, r->streams[i].confidence) << i;
  }
}

TEST(RunEvaluation, SensorTestViewsAndTheRobustnessMatrix) {
  const std::vector<EvalObject> objects = zoo_objects(4, 3);
  EvalParams p = reduced_params();
  p.methods = {MethodId::kFusion};
  p.stages = {{StageKind::kFull, 0}, {StageKind::kFraction, 0.1}, {StageKind::kFraction, 0.2}};
  p.explore_max_keypoints = 0;
  p.stream_chunk_fraction = 0;
  p.test_condition.sensor = SensorKind::kDepthCamera;
  p.test_condition.distance_m = 2.5f;
  ScanCondition floor = p.test_condition;
  floor.floor = true, floor.outliers = 0.02;
  p.matrix = {ScanCondition{}, floor};
  p.matrix_views_per_object = 1;
  p.train_conditions = default_training_sensors();  // the recipe: the model learns a camera's views too
  auto r = run_evaluation(objects, p, "zoo, depth camera");
  ASSERT_TRUE(r.ok()) << r.error().message;
  // The tested views are the depth camera's, filtered to the training density; stages keep their share.
  ASSERT_EQ(r->trained_density.size(), 2u);
  for (double d : r->trained_density) EXPECT_GT(d, 100.0);
  for (const StageDecision& d : r->decisions)
    if (d.stage == "10%") {
      EXPECT_NEAR(d.visible_fraction, 0.10, 5e-3);  // rounding on small parts
    }
  const double full = accuracy(r->decisions, "full", MethodId::kFusion).percent();
  // The matrix: one row per condition, one view per object; the floor is found and removed.
  ASSERT_EQ(r->robustness.size(), 2u);
  for (const RobustnessRow& row : r->robustness) {
    EXPECT_EQ(row.views, objects.size());
    ASSERT_EQ(row.accuracy.size(), p.stages.size());
  }
  const RobustnessRow& ideal = r->robustness[0];
  const RobustnessRow& residue = r->robustness[1];
  EXPECT_EQ(ideal.ground_views, 0u);
  EXPECT_GE(residue.ground_views, objects.size() * 9 / 10);
  EXPECT_GT(residue.median_points_raw, 3 * residue.median_points);  // the floor and density filtered out
  const std::string md = markdown_report(*r);
  EXPECT_NE(md.find("## Robustness matrix"), std::string::npos);
  EXPECT_NE(md.find("depth camera 2.5 m, 30 deg, floor, 2 % outliers"), std::string::npos);
  EXPECT_NE(md.find("## Test views from a simulated sensor"), std::string::npos);
  std::cout << "zoo, depth camera test views: fusion full " << full << " %; matrix ideal full " << ideal.accuracy[0]
            << " %, 20 % " << ideal.accuracy[2] << " %; floor + outliers full " << residue.accuracy[0] << " %, 20 % "
            << residue.accuracy[2] << " % (ground on " << residue.ground_views << " of " << residue.views << ")\n";
  // Measured (zoo 4 per category, seed 3, 2 folds, 3 views, 3000 points, the recipe's training sensors and
  // logistic decision): depth camera test views 95.0 % full (60 views, one is 1.7 points); matrix (20
  // views, one is 5 points): ideal 95 / 95 (full / 20 %), depth camera with floor and 2 % outliers
  // 85 / 85. Before the cameras' training views were thinned to the model's one density (stop 47), each
  // to its object's own ideal views': 95.0; 100 / 100; 90 / 85 (81.7, 80 / 75, 80 / 80 with neither).
  EXPECT_GE(full, 93.0);                      // measured 95.0
  EXPECT_GE(residue.accuracy[0], 80.0);       // measured 85 (90 before stop 47)
  EXPECT_GE(residue.accuracy[2], 80.0);       // measured 85
  // Same answers on one thread, and without the novelty models (which the size-blind ablation skips):
  // they weigh on novelty alone, never on a decision's scores.
  EXPECT_EQ(r->novelty_models, 2u);  // each fold's model learnt the ideal views apart
  EvalParams one = p;
  one.threads = 1;
  one.novelty_models = false;
  auto r1 = run_evaluation(objects, one, "zoo, depth camera");
  ASSERT_TRUE(r1.ok());
  EXPECT_EQ(r1->novelty_models, 0u);
  for (size_t i = 0; i < r->robustness.size(); ++i) EXPECT_EQ(r1->robustness[i].accuracy, r->robustness[i].accuracy);
  ASSERT_EQ(r1->decisions.size(), r->decisions.size());
  for (size_t i = 0; i < r->decisions.size(); ++i) EXPECT_EQ(r1->decisions[i].scores, r->decisions[i].scores) << i;
}

std::vector<EvalObject> with_role(std::vector<EvalObject> objects, EvalRole role, const std::string& source) {
  for (EvalObject& o : objects) o.role = role, o.source = source;
  return objects;
}

TEST(RunEvaluation, CrossSourceTrainsOneModelOnOneSourceAndTestsOnlyTheOther) {
  std::vector<EvalObject> objects = with_role(zoo_objects(4, 3), EvalRole::kTrainOnly, "zoo-a");
  const std::vector<EvalObject> test = with_role(zoo_objects(3, 9), EvalRole::kTestOnly, "zoo-b");
  objects.insert(objects.end(), test.begin(), test.end());
  EvalParams p = reduced_params();
  p.methods = {MethodId::kUSH, MethodId::kSize, MethodId::kFusion};
  p.stages = {{StageKind::kFull, 0}, {StageKind::kFraction, 0.1}, {StageKind::kFraction, 0.2}};
  p.explore_max_keypoints = 0;
  auto r = run_evaluation(objects, p, "two zoos");
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_TRUE(r->cross_source);
  EXPECT_EQ(r->train_sources, std::vector<std::string>{"zoo-a"});
  EXPECT_EQ(r->test_sources, std::vector<std::string>{"zoo-b"});
  EXPECT_EQ(r->settle_margins.size(), 1u);  // one model, not one per fold
  // Only the test source's views are decided, each once per stage and method, by the one model.
  EXPECT_EQ(r->decisions.size(), test.size() * p.views_per_object * p.stages.size() * p.methods.size());
  for (const StageDecision& d : r->decisions) {
    EXPECT_EQ(d.fold, 0);
    EXPECT_EQ(r->object_source[static_cast<size_t>(d.object)], "zoo-b");
  }
  EXPECT_EQ(r->streams.size(), test.size() * p.views_per_object);
  const std::string report = markdown_report(*r);
  EXPECT_NE(report.find("cross-source"), std::string::npos);
  EXPECT_NE(report.find("How much is size"), std::string::npos);
  // The data row counts both sides (the cross-source row splits them), and says so.
  EXPECT_NE(report.find("(" + std::to_string(objects.size()) + " objects learnt and tested in all: "), std::string::npos);
  // Chance is 20 %: a model of 4 zoo objects per category on 3 others of another seed (45 views, one is
  // 2.2 points). Measured: fusion full / 20 % 86.7 / 95.6 (86.7 / 86.7 before the fusion's logistic
  // decision was the default), USH full 91.1, size only full 60.0.
  const double fusion_full = accuracy(r->decisions, "full", MethodId::kFusion).percent();
  const double fusion_20 = accuracy(r->decisions, "20%", MethodId::kFusion).percent();
  std::cout << "two zoos: fusion full " << fusion_full << " %, 20 % " << fusion_20 << " %, size only full "
            << accuracy(r->decisions, "full", MethodId::kSize).percent() << " %, USH full "
            << accuracy(r->decisions, "full", MethodId::kUSH).percent() << " %\n";
  EXPECT_GE(fusion_full, 82.0);  // measured 86.7
  EXPECT_GE(fusion_20, 93.0);    // measured 95.6
  // Cross-validated and test-only objects do not mix; training-only ones may join a cross-validation.
  std::vector<EvalObject> mixed = with_role(zoo_objects(2, 3), EvalRole::kCrossValidate, "zoo-a");
  mixed.push_back(test.front());
  EXPECT_FALSE(run_evaluation(mixed, p, "mixed").ok());
  std::vector<EvalObject> only_train = with_role(zoo_objects(1, 3), EvalRole::kTrainOnly, "zoo-a");
  EXPECT_FALSE(run_evaluation(only_train, p, "no test").ok());
}

TEST(OpenSet, SummaryOnAHandMadeList) {
  auto make = [](int truth, int unknown_class, int winner, double novelty, bool unknown) {
    StageDecision d;
    d.stage = "full";
    d.method = MethodId::kFusion;
    d.truth = truth;
    d.unknown_class = unknown_class;
    d.winner = winner;
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

// The CI's open-set check: one zoo category is held out of every model and tested as unknown; its views
// must come out more novel than the known ones' (novelty calibrated on held-out folds of the training
// views only, each decided untilted as a test view comes). Zoo 8 per category, seed 3, 2 folds, 3 views,
// 3000 points, fusion. Measured: AUROC 0.751 on full views, 0.902 at 20 % visible with distances over a
// category's nearest training objects (0.697 / 0.863 from its nearest reference alone, 0.569 / 0.670
// before novelty was divided by the decision's score, 0.620 at 20 % when the held-out views were decided
// tilted; the zoo's four-legged animals share legs and backs with its chairs and tables); 95.8 % of known
// and 79.2 % of unknown full views accepted at the default operating point. With the top-down prefix's
// novelty (below): AUROC 0.876 and 0.909, 99.0 % and 83.3 % accepted.
TEST(RunEvaluation, AZooCategoryHeldOutComesOutNovel) {
  std::vector<EvalObject> objects = zoo_objects(8, 3);
  for (EvalObject& o : objects)
    if (o.category == "fourleg") o.role = EvalRole::kUnknown;
  EvalParams p = reduced_params();
  p.methods = {MethodId::kFusion};
  p.stages = {{StageKind::kFull, 0}, {StageKind::kFraction, 0.2}};
  p.explore_max_keypoints = 0;
  p.stream_chunk_fraction = 0.05;
  auto r = run_evaluation(objects, p, "zoo without fourleg");
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->categories.size(), 4u);
  EXPECT_EQ(r->unknown_categories, std::vector<std::string>{"fourleg"});
  size_t unknown_views = 0;
  for (const StageDecision& d : r->decisions)
    if (d.truth < 0) {
      ++unknown_views;
      EXPECT_EQ(d.unknown_class, 0);
      EXPECT_TRUE(std::isfinite(d.novelty) || d.winner < 0);
    }
  EXPECT_EQ(unknown_views, 8u * 3 * 2);  // 8 objects, 3 views, 2 stages
  const std::vector<OpenSetRow> rows = open_set_summary(r->decisions, p.stages, MethodId::kFusion, 1);
  ASSERT_EQ(rows.size(), 2u);
  std::cout << "zoo, fourleg unknown: AUROC full " << rows[0].auroc << ", 20 % " << rows[1].auroc
            << "; known accepted " << rows[0].known_acceptance << " %, unknown accepted " << rows[0].false_acceptance
            << " % (full)\n";
  // Measured 0.876 and 0.909 since the top-down prefix's novelty joins the cloud's (TrainParams::
  // novelty_prefix, chosen on SHREC: this test's zoo was not looked at); 0.746 and 0.896 before (0.744 and
  // 0.898 with the larger of novelty's evidences; 0.751 and 0.902 before the fusion's logistic decision).
  EXPECT_GE(rows[0].auroc, 0.86);
  EXPECT_GE(rows[1].auroc, 0.90);
  const std::string report = markdown_report(*r);
  EXPECT_NE(report.find("## Open set"), std::string::npos);
  EXPECT_NE(decisions_csv(*r).find(",unknown:fourleg,"), std::string::npos);
  // Their views are streamed too, and the known streams' metrics leave them out.
  EXPECT_EQ(r->streams.size(), 8u * 4 * 3 + 8u * 3);
  EXPECT_EQ(settle_summary(r->streams, -1).views, 8u * 4 * 3);
  const SettleRow streamed = unknown_settle_summary(r->streams);
  EXPECT_EQ(streamed.views, 8u * 3);
  std::cout << "zoo, fourleg unknown, streams: " << streamed.settled_views << " of " << streamed.views << " settled, "
            << streamed.correct << " as unknown\n";
  // Few settle "unknown" here (the zoo's fourlegs look like its tables and humans, AUROC 0.88 above): 11
  // of the 24 settle, none as unknown (13 before the top-down prefix's novelty; 16 and 2 before settling
  // was cautious both ways, stop 42). What a test can hold is that the caution does not settle more of
  // them on a category than before (14).
  const size_t on_a_category = streamed.settled_views - streamed.correct;
  EXPECT_LE(on_a_category, 12u);  // measured 11
  EXPECT_NE(report.find("Objects of no learnt category, streamed"), std::string::npos);
  const std::string csv = streams_csv(*r);
  EXPECT_NE(csv.find(",unknown:fourleg,"), std::string::npos);
  // Each chunk's novelty beside its unknown flag: a flagged chunk's is above every unflagged one's of its model.
  EXPECT_NE(csv.find(",unknown,novelty\n"), std::string::npos);
  for (int fold = 0; fold < p.folds; ++fold) {
    double accepted = 0, rejected = INFINITY;
    for (const StreamTrace& t : r->streams)
      for (size_t i = 0; t.fold == fold && i < t.novelty.size(); ++i)
        if (!std::isfinite(t.novelty[i])) continue;
        else if (t.unknown[i]) rejected = std::min(rejected, t.novelty[i]);
        else accepted = std::max(accepted, t.novelty[i]);
    EXPECT_LT(accepted, rejected) << "fold " << fold;
  }
}

// USH alone at full view and 20 %, no exploration, streams or matrix: what the training-view tests vary.
EvalParams ush_training_params() {
  EvalParams p = reduced_params();
  p.methods = {MethodId::kUSH};
  p.stages = {{StageKind::kFull, 0}, {StageKind::kFraction, 0.2}};
  p.explore_max_keypoints = 0;
  p.stream_chunk_fraction = 0;
  p.matrix.clear();
  return p;
}

// Training views from other elevations are learnt, never tested: the same decisions are taken, each
// model trains on the extra views (and their prefixes) too.
TEST(RunEvaluation, TrainingElevationsAddTrainingViewsAndNoTestedOnes) {
  const std::vector<EvalObject> objects = zoo_objects(2, 3);
  EvalParams p = ush_training_params();
  auto samples = [](const EvalResult& r) {
    for (const PhaseTiming& t : r.timings)
      if (t.phase == "train (all folds)") return std::stoul(t.detail);
    return 0ul;
  };
  auto plain = run_evaluation(objects, p, "zoo");
  p.train_elevations_deg = {0.f, 60.f};
  auto raised = run_evaluation(objects, p, "zoo");
  ASSERT_TRUE(plain.ok() && raised.ok());
  ASSERT_EQ(raised->decisions.size(), plain->decisions.size());
  for (size_t i = 0; i < plain->decisions.size(); ++i) {
    EXPECT_EQ(raised->decisions[i].object, plain->decisions[i].object);
    EXPECT_EQ(raised->decisions[i].view, plain->decisions[i].view);
    EXPECT_EQ(raised->decisions[i].points, plain->decisions[i].points);  // the tested views are the same
  }
  const std::string views = std::find_if(raised->timings.begin(), raised->timings.end(), [](const PhaseTiming& t) {
                              return t.phase == "HPR views";
                            })->detail;
  const size_t extra = 2 * objects.size() * p.views_per_object;
  EXPECT_NE(views.find("(" + std::to_string(extra) + " for training only)"), std::string::npos) << views;
  EXPECT_GT(samples(*raised), 2 * samples(*plain));  // three elevations' views and prefixes, a few too small
}

// Training views of a simulated sensor are learnt, never tested: the tested views stay the ideal ones,
// each model trains on a depth camera's filtered views (and their prefixes) too.
TEST(RunEvaluation, TrainingSensorViewsAreLearntAndNeverTested) {
  const std::vector<EvalObject> objects = zoo_objects(2, 3);
  EvalParams p = ush_training_params();
  auto timing = [](const EvalResult& r, const std::string& phase) {
    for (const PhaseTiming& t : r.timings)
      if (t.phase == phase) return t.detail;
    return std::string();
  };
  auto plain = run_evaluation(objects, p, "zoo");
  ScanCondition depth;
  depth.sensor = SensorKind::kDepthCamera, depth.distance_m = 1.5f, depth.elevation_deg = 15.f;
  p.train_conditions = {depth};
  auto sensed = run_evaluation(objects, p, "zoo");
  ASSERT_TRUE(plain.ok() && sensed.ok());
  ASSERT_EQ(sensed->decisions.size(), plain->decisions.size());
  for (size_t i = 0; i < plain->decisions.size(); ++i) {
    EXPECT_EQ(sensed->decisions[i].object, plain->decisions[i].object);
    EXPECT_EQ(sensed->decisions[i].points, plain->decisions[i].points);  // the tested views are the ideal ones
  }
  EXPECT_TRUE(timing(*plain, "sensor training views").empty());
  const std::string made = timing(*sensed, "sensor training views");
  const size_t extra = objects.size() * p.views_per_object;
  EXPECT_EQ(made.find(std::to_string(extra) + " views: depth camera 1.5 m, 15 deg"), 0u) << made;
  const size_t learnt = std::stoul(timing(*plain, "train (all folds)"));
  EXPECT_GT(std::stoul(timing(*sensed, "train (all folds)")), learnt + learnt / 2);  // the camera's views and prefixes
}

TEST(Objects, CommonHeightMakesEveryObjectOneHeightOnTheGround) {
  for (const EvalObject& o : common_height(zoo_objects(1, 5), 1.0f)) {
    const Bounds b = bounds(o.mesh.vertices);
    EXPECT_NEAR(b.extent().z(), 1.0f, 1e-5f) << o.category;
    EXPECT_NEAR(b.min.z(), 0.0f, 1e-6f);
  }
}

std::string shrec_dir() {
  if (const char* env = std::getenv("GLIMPSE_SHREC_DIR")) return env;
  return GLIMPSE_SOURCE_DIR "/../shared/data/shrec07";
}

TEST(RunEvaluation, ReducedProtocolOnShrec) {
  const std::string dir = shrec_dir();
  if (!std::filesystem::is_directory(dir))
    GTEST_SKIP() << "SHREC 2007 not found at " << dir << " (set GLIMPSE_SHREC_DIR to run this test)";
  auto objects = load_dataset_objects(dir, 42, 10);
  ASSERT_TRUE(objects.ok()) << objects.error().message;
  EvalParams p = reduced_params();
  p.methods = {MethodId::kBoK, MethodId::kFusion};
  p.seed = 42;
  p.train_conditions = default_training_sensors();  // the recipe's training views
  auto r = run_evaluation(*objects, p, "shrec");
  ASSERT_TRUE(r.ok()) << r.error().message;
  // Floors just under what was measured (10 objects per category, 2 folds, 3 views, 3000 points, seed 42;
  // 150 test views, one is 0.7 points; the recipe's training sensors and logistic decision); raise them
  // as recognition improves.
  // Stop 47: the cameras' training views thinned to the model's one density, not each to its object's own
  // ideal views': fusion 95.3 -> 98.0 on full views; BoK, which learns the cameras' views too in this
  // recipe (not in the paper's: --preset paper has none), 59.3 -> 48.7: its keypoints follow the density.
  EXPECT_GE(accuracy(r->decisions, "full", MethodId::kFusion).percent(), 97.0);  // measured 98.0 (95.3 before stop 47 and before both)
  EXPECT_GE(accuracy(r->decisions, "20%", MethodId::kFusion).percent(), 97.0);   // measured 98.0 (98.0; 96.0)
  EXPECT_GE(accuracy(r->decisions, "full", MethodId::kBoK).percent(), 47.5);     // measured 48.7 (59.3 at stop 39, 52.0 when set, stop 34)
  const SettleRow settled = settle_summary(r->streams, -1);
  // Settling needs the winner to hold a whole window, the newest chunk included: later, righter.
  // "Unknown" settles like a category and counts wrong here (every view is known): 79.3 % settled, 90.8 %
  // right, at 11.5 % visible once "unknown" needs the newest chunk's own novelty too; 80.7 % settled,
  // 89.3 % right, at 11.4 % visible before (76.7 / 94.8 / 11.6 before novelty was divided by the decision's
  // score); without it 78.7 / 97.5 / 10.6 (86.7 / 97.7 / 10.2 before the calibration decided held-out
  // clouds untilted, as they come from a sensor). With the recipe's training sensors and the fusion's
  // logistic decision: 95.3 % settled, 96.5 % right, at 11.9 % visible. With novelty from the novelty
  // model (the cameras' views augmented, stop 36): 95.3 % settled, 94.4 % right, at 11.8 % visible (more
  // known views settle "unknown": the threshold is the ideal views', no longer widened by the cameras').
  // Novelty adding its two evidences (format 9): 95.3 % settled, 95.1 % right, at 11.9 % visible.
  // Settling cautious both ways (stop 42): 94.0 % settled, 97.9 % right, at 12.5 % visible. The cameras'
  // views at the model's one density (stop 47): 94.0 %, 97.9 %, at 12.0 % visible. The logistic fit's
  // tolerance 1e-3 (stop 50): 94.0 %, 97.9 %, at 12.1 % visible.
  EXPECT_GE(settled.settled_percent(), 93.0);    // measured 94.0 (141 of 150 views; 95.3 before)
  EXPECT_GE(settled.precision_percent(), 97.5);  // measured 97.9 (138 of 141; 95.1 before)
  EXPECT_LE(settled.mean_visible_percent, 12.5); // measured 12.1 (12.0 before stop 50, 12.5 before stop 47, 11.9 before)
  std::cout << "shrec reduced: full fusion " << accuracy(r->decisions, "full", MethodId::kFusion).percent()
            << " %, 20 % fusion " << accuracy(r->decisions, "20%", MethodId::kFusion).percent() << " %, full BoK "
            << accuracy(r->decisions, "full", MethodId::kBoK).percent() << " %; streams settled "
            << settled.settled_percent() << " % at " << settled.mean_visible_percent << " % visible, precision "
            << settled.precision_percent() << " %\n";
}

std::string psb_dir() {
  if (const char* env = std::getenv("GLIMPSE_PSB_DIR")) return env;
  return GLIMPSE_SOURCE_DIR "/../shared/data/psb";
}

// The world is not SHREC: a model of SHREC objects judged on another collection (PSB and ABC parts).
TEST(RunEvaluation, ReducedCrossSourceShrecToPsb) {
  const std::string train_dir = shrec_dir(), test_dir = psb_dir();
  if (!std::filesystem::is_directory(train_dir) || !std::filesystem::is_directory(test_dir))
    GTEST_SKIP() << "SHREC 2007 (" << train_dir << ") or PSB (" << test_dir
                 << ") not found (set GLIMPSE_SHREC_DIR / GLIMPSE_PSB_DIR to run this test)";
  auto train = load_dataset_objects(train_dir, 42, 10);
  auto test = load_dataset_objects(test_dir, 42, 8);
  ASSERT_TRUE(train.ok()) << train.error().message;
  ASSERT_TRUE(test.ok()) << test.error().message;
  std::vector<EvalObject> objects;
  for (EvalObject& o : *train) o.role = EvalRole::kTrainOnly, objects.push_back(std::move(o));
  for (EvalObject& o : *test) o.role = EvalRole::kTestOnly, objects.push_back(std::move(o));
  EvalParams p = reduced_params();
  p.methods = {MethodId::kSize, MethodId::kFusion};
  p.stages = {{StageKind::kFull, 0}, {StageKind::kFraction, 0.1}, {StageKind::kFraction, 0.2}};
  p.explore_max_keypoints = 0;
  p.seed = 42;
  p.train_conditions = default_training_sensors();  // the recipe's training views
  auto r = run_evaluation(objects, p, "shrec -> psb");
  ASSERT_TRUE(r.ok()) << r.error().message;
  const double full = accuracy(r->decisions, "full", MethodId::kFusion).percent();
  const double p10 = accuracy(r->decisions, "10%", MethodId::kFusion).percent();
  const double p20 = accuracy(r->decisions, "20%", MethodId::kFusion).percent();
  const double size = accuracy(r->decisions, "full", MethodId::kSize).percent();
  const SettleRow settled = settle_summary(r->streams, -1);
  std::cout << "shrec -> psb reduced: fusion full " << full << " %, 10 % " << p10 << " %, 20 % " << p20
            << " %, size only full " << size << " %; streams settled " << settled.settled_percent() << " % at "
            << settled.mean_visible_percent << " % visible, precision " << settled.precision_percent() << " %\n";
  // 10 SHREC objects per category -> 8 PSB objects per category (6 parts), 3 views, 3000 points, seed 42:
  // 114 test views, one is 0.9 points. Measured with the recipe's training sensors and the fusion's logistic
  // decision: fusion 93.0 / 95.6 / 98.2 (full / 10 % / 20 %; 92.1 / 93.0 / 92.1 with neither), size only
  // 68.4 on full views (71.1); streams settle on 97.4 % of views at 10.7 % visible, 97.3 % of them right.
  // With the cameras' training views thinned to the model's one density (stop 47): fusion 99.1 / 97.4 /
  // 99.1, size only 72.8 (it learns the cameras' extents too), streams 93.0 % settled, 98.1 % right.
  EXPECT_GE(full, 98.0);  // measured 99.1 (93.0 before stop 47)
  EXPECT_GE(p10, 96.0);   // measured 97.4 (95.6)
  EXPECT_GE(p20, 98.0);   // measured 99.1 (98.2)
  EXPECT_GT(full, size + 15);  // shape adds to what a ruler gets right
  EXPECT_GE(settled.settled_percent(), 92.0);    // measured 93.0 (92.1 before stop 47; 94.7 before the top-down prefix's novelty joined the cloud's; 97.4 before settling was cautious both ways, stop 42; 99.1 with neither, 98.2 before "unknown" needed the newest chunk's novelty)
  // Settled as "unknown" counts wrong: 92.0 since "unknown" needs the newest chunk's own novelty too
  // (86.0 before; 91.1 before novelty was divided by the decision's score, 97.3 before unknown could settle);
  // 92.0 before the recipe's training sensors and logistic decision, 97.3 with them; 92.8 since novelty
  // comes from the novelty model (stop 36: the cameras' views augmented; PSB views look more novel to a
  // model of SHREC's ideal views alone, and more settle "unknown"); 93.7 since novelty adds its two
  // evidences (format 9); 97.2 since settling is cautious both ways (stop 42: fewer known views settle
  // "unknown", and a category settles only on a novelty well inside the threshold); 97.1 since the
  // top-down prefix's novelty joins the cloud's.
  // 98.1 with the cameras' views at the model's one density (stop 47).
  EXPECT_GE(settled.precision_percent(), 97.0);  // measured 98.1 (97.1 before stop 47; 97.2, 105 of 108; 93.7, 104 of 111, before)
}

}  // namespace
}  // namespace glimpse

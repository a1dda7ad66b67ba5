// The evaluation protocol end to end on the zoo: folds, stage cuts, streams, sensors and the robustness
// matrix, cross-source runs, a category held out as unknown, training-only views.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <set>
#include <string>

#include "glimpse/geometry/scan_filters.h"
#include "glimpse/lab/evaluation.h"
#include "reduced_params.h"

namespace glimpse {
namespace {

using testing::reduced_params;

// ---- end to end ------------------------------------------------------------------------------------

TEST(RunEvaluation, RejectsBadInput) {
  EXPECT_FALSE(run_evaluation({}, {}, "none").ok());
  EvalParams one_fold;
  one_fold.folds = 1;
  EXPECT_FALSE(run_evaluation(zoo_objects(1, 1), one_fold, "zoo").ok());
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
  // full view fusion 95.0 %, VFH 55.0 %, 20 % visible fusion 93.3 % (83.3 / 83.3 without the fusion's
  // logistic decision); streams: 71.7 % settle, at 11.7 % visible on average, all right.
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
  // held-out known clouds). Settling is cautious both ways ("unknown" after 6 chunks at confidence 1, the
  // newest chunk's own novelty above the threshold too; a category at novelty <= 0.8 x the threshold): 43
  // of the 60 views settle, all right.
  EXPECT_GE(settled.precision_percent(), 97.0);  // measured 100 (43 of the 60 views settled)
  EXPECT_GE(settled.settled_percent(), 70.0);    // measured 71.7
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
  ScanCondition lidar;
  lidar.sensor = SensorKind::kLidar, lidar.beams = 64, lidar.distance_m = 5.f, lidar.elevation_deg = 5.f;
  p.matrix = {ScanCondition{}, floor, lidar};
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
  ASSERT_EQ(r->robustness.size(), 3u);
  for (const RobustnessRow& row : r->robustness) {
    EXPECT_EQ(row.views, objects.size());
    ASSERT_EQ(row.accuracy.size(), p.stages.size());
    ASSERT_EQ(row.accepted.size(), p.stages.size());
    for (size_t s = 0; s < p.stages.size(); ++s) EXPECT_LE(row.accepted[s], row.accuracy[s]) << describe(row.condition);
    EXPECT_TRUE(std::isnan(row.unknown_accepted));  // every object is of a learnt category
    ASSERT_EQ(row.full_views.size(), objects.size());
    size_t right = 0;
    for (const RobustnessRow::ViewOutcome& v : row.full_views) {
      right += v.right;
      EXPECT_TRUE(v.right || !v.accepted);
    }
    EXPECT_NEAR(100.0 * double(right) / double(objects.size()), row.accuracy[0], 1e-9);
  }
  // A 64-beam LiDAR at 5 m leaves fewer points than a depth camera, still enough to decide most views.
  EXPECT_LT(r->robustness[2].median_points, r->robustness[1].median_points);
  EXPECT_GT(r->robustness[2].median_points, 50.0);
  const RobustnessRow& ideal = r->robustness[0];
  const RobustnessRow& residue = r->robustness[1];
  EXPECT_EQ(ideal.ground_views, 0u);
  EXPECT_GE(residue.ground_views, objects.size() * 9 / 10);
  EXPECT_GT(residue.median_points_raw, 3 * residue.median_points);  // the floor and density filtered out
  const std::string md = markdown_report(*r);
  EXPECT_NE(md.find("## Robustness matrix"), std::string::npos);
  EXPECT_NE(md.find("depth camera 2.5 m, 30 deg, floor, 2 % outliers"), std::string::npos);
  EXPECT_NE(md.find("| LiDAR 64 beams 5 m, 5 deg |"), std::string::npos);
  EXPECT_NE(md.find("right and accepted full / 10% / 20%"), std::string::npos) << md;
  EXPECT_NE(md.find("| points kept | depth camera | LiDAR |"), std::string::npos);
  EXPECT_NE(md.find("## Test views from a simulated sensor"), std::string::npos);
  std::cout << "zoo, depth camera test views: fusion full " << full << " %; matrix ideal full " << ideal.accuracy[0]
            << " %, 20 % " << ideal.accuracy[2] << " %; floor + outliers full " << residue.accuracy[0] << " %, 20 % "
            << residue.accuracy[2] << " % (ground on " << residue.ground_views << " of " << residue.views << ")\n";
  // Measured (zoo 4 per category, seed 3, 2 folds, 3 views, 3000 points, the recipe's training sensors and
  // logistic decision): depth camera test views 90.0 % full (60 views, one is 1.7 points); matrix (20
  // views, one is 5 points): ideal 90 / 95 (full / 20 %), depth camera with floor and 2 % outliers
  // 85 / 85 (the sensors' training views thinned to the model's one density).
  EXPECT_GE(full, 88.0);                      // measured 90.0
  EXPECT_GE(residue.accuracy[0], 80.0);       // measured 85
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
  EXPECT_NE(report.find('(' + std::to_string(objects.size()) + " objects learnt and tested in all: "), std::string::npos);
  // Chance is 20 %: a model of 4 zoo objects per category on 3 others of another seed (45 views, one is
  // 2.2 points). Measured: fusion full / 20 % 86.7 / 95.6 (86.7 / 86.7 without the fusion's logistic
  // decision), USH full 91.1, size only full 60.0.
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

// The CI's open-set check: one zoo category is held out of every model and tested as unknown; its views
// must come out more novel than the known ones' (novelty calibrated on held-out folds of the training
// views only, each decided untilted as a test view comes). Zoo 8 per category, seed 3, 2 folds, 3 views,
// 3000 points, fusion. Measured: AUROC 0.751 on full views, 0.902 at 20 % visible with distances over a
// category's nearest training objects (0.697 / 0.863 from its nearest reference alone, 0.569 / 0.670
// without dividing novelty by the decision's score, 0.620 at 20 % with the held-out views decided
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
  // Measured 0.876 and 0.909 with the top-down prefix's novelty joined to the cloud's (TrainParams::
  // novelty_prefix, chosen on SHREC: this test's zoo is not looked at); 0.746 and 0.896 without it.
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
  // of the 24 settle, none as unknown (13 without the top-down prefix's novelty). What a test can hold is
  // that the cautious settling keeps them off a category: 14 settle on one when "unknown" and a category
  // settle alike.
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

// The samples each model learnt, as the run's "train (all folds)" timing counts them.
unsigned long trained_samples(const EvalResult& r) {
  for (const PhaseTiming& t : r.timings)
    if (t.phase == "train (all folds)") return std::stoul(t.detail);
  return 0ul;
}

// Training views from other elevations are learnt, never tested: the same decisions are taken, each
// model trains on the extra views (and their prefixes) too.
TEST(RunEvaluation, TrainingElevationsAddTrainingViewsAndNoTestedOnes) {
  const std::vector<EvalObject> objects = zoo_objects(2, 3);
  EvalParams p = ush_training_params();
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
  EXPECT_NE(views.find('(' + std::to_string(extra) + " for training only)"), std::string::npos) << views;
  EXPECT_GT(trained_samples(*raised), 2 * trained_samples(*plain));  // three elevations' views and prefixes, a few too small
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

// Few-shot: a model learns at most K objects of each category and tests what it always tests. K at or
// above what a fold could learn changes nothing.
TEST(RunEvaluation, FewShotModelsLearnAtMostKObjectsPerCategoryAndTestTheSame) {
  const std::vector<EvalObject> objects = zoo_objects(4, 3);  // two folds: 2 learnable per category
  EvalParams p = ush_training_params();
  auto all = run_evaluation(objects, p, "zoo");
  p.objects_per_category = 2;
  auto two = run_evaluation(objects, p, "zoo");
  p.objects_per_category = 1;
  auto one = run_evaluation(objects, p, "zoo");
  ASSERT_TRUE(all.ok() && two.ok() && one.ok());
  ASSERT_EQ(one->decisions.size(), all->decisions.size());
  for (size_t i = 0; i < all->decisions.size(); ++i) {
    EXPECT_EQ(one->decisions[i].object, all->decisions[i].object);  // the same tested views
    EXPECT_EQ(one->decisions[i].points, all->decisions[i].points);
    EXPECT_EQ(two->decisions[i].winner, all->decisions[i].winner);
  }
  EXPECT_EQ(trained_samples(*two), trained_samples(*all));
  EXPECT_GT(trained_samples(*one), trained_samples(*all) * 4 / 10);  // one object of two, give or take a too-small prefix
  EXPECT_LT(trained_samples(*one), trained_samples(*all) * 6 / 10);
}

}  // namespace
}  // namespace glimpse

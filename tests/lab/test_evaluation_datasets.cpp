// The evaluation protocol on real collections, reduced: SHREC 2007 cross-validated and SHREC -> PSB, with
// floors just under what is measured (skipped when the data is absent).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "glimpse/lab/evaluation.h"
#include "reduced_params.h"

namespace glimpse {
namespace {

using testing::reduced_params;

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
  // Floors just under what is measured (10 objects per category, 2 folds, 3 views, 3000 points, seed 42;
  // 150 test views, one is 0.7 points; the recipe's training sensors and logistic decision); raise them
  // as recognition improves. The cameras' training views are thinned to the model's one density (each to
  // its object's own ideal views' instead: fusion 95.3 on full views; BoK, which learns the cameras' views
  // too in this recipe, not in the paper's, 59.3: its keypoints follow the density).
  EXPECT_GE(accuracy(r->decisions, "full", MethodId::kFusion).percent(), 97.5);  // measured 98.0
  EXPECT_GE(accuracy(r->decisions, "20%", MethodId::kFusion).percent(), 97.5);   // measured 98.0
  EXPECT_GE(accuracy(r->decisions, "full", MethodId::kBoK).percent(), 40.5);     // measured 41.3
  const SettleRow settled = settle_summary(r->streams, -1);
  // Settling needs the winner to hold a whole window, the newest chunk included: later, righter.
  // "Unknown" settles like a category and counts wrong here (every view is known). Novelty comes from the
  // novelty model (the cameras' views augmented: the threshold is the ideal views', not widened by the
  // cameras'), and settling is cautious both ways. The held-out decisions the settle probability is
  // calibrated on include the sensors' sparse and cut views, which raise it: 76.0 % settled, 99.1 %
  // right, at 12.9 % visible (the full SHREC CV: 95.8 % settled, 99.1 % right; docs/results.md).
  EXPECT_GE(settled.settled_percent(), 75.0);    // measured 76.0 (114 of 150 views)
  EXPECT_GE(settled.precision_percent(), 98.5);  // measured 99.1 (113 of 114)
  EXPECT_LE(settled.mean_visible_percent, 13.5); // measured 12.9
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
  // decision, the cameras' training views thinned to the model's one density: fusion 98.2 / 96.5 / 98.2
  // (full / 10 % / 20 %), size only 71.1 on full views (it learns the sensors' extents too); streams
  // settle on 87.7 % of views, 99.0 % of them right.
  EXPECT_GE(full, 97.5);  // measured 98.2
  EXPECT_GE(p10, 95.5);   // measured 96.5
  EXPECT_GE(p20, 97.5);   // measured 98.2
  EXPECT_GT(full, size + 15);  // shape adds to what a ruler gets right
  EXPECT_GE(settled.settled_percent(), 87.0);    // measured 87.7
  // Settled as "unknown" counts wrong. Novelty comes from the novelty model (the cameras' views
  // augmented: PSB views look more novel to a model of SHREC's ideal views alone), and settling is
  // cautious both ways (fewer known views settle "unknown", and a category settles only on a novelty well
  // inside the threshold).
  EXPECT_GE(settled.precision_percent(), 98.0);  // measured 99.0
}

std::string psb_other_dir() {
  if (const char* env = std::getenv("GLIMPSE_PSB_OTHER_DIR")) return env;
  return GLIMPSE_SOURCE_DIR "/../shared/data/psb-other";
}

// "Unknown" across collections: a model of SHREC objects (and the recipe's training cameras) judged on
// PSB's known categories and on ten PSB categories it never learnt. Novelty must rank the new
// categories above the other collection's known views, and the operating point must keep most of
// those known views.
TEST(RunEvaluation, ReducedCrossSourceOpenSet) {
  const std::string train_dir = shrec_dir(), test_dir = psb_dir(), unknown_dir = psb_other_dir();
  for (const std::string& dir : {train_dir, test_dir, unknown_dir})
    if (!std::filesystem::is_directory(dir))
      GTEST_SKIP() << dir << " not found (set GLIMPSE_SHREC_DIR / GLIMPSE_PSB_DIR / GLIMPSE_PSB_OTHER_DIR)";
  auto train = load_dataset_objects(train_dir, 42, 10);
  auto test = load_dataset_objects(test_dir, 42, 8);
  auto unknown = load_dataset_objects(unknown_dir, 42, 4);
  ASSERT_TRUE(train.ok()) << train.error().message;
  ASSERT_TRUE(test.ok()) << test.error().message;
  ASSERT_TRUE(unknown.ok()) << unknown.error().message;
  std::vector<EvalObject> objects;
  for (EvalObject& o : *train) o.role = EvalRole::kTrainOnly, objects.push_back(std::move(o));
  for (EvalObject& o : *test) o.role = EvalRole::kTestOnly, objects.push_back(std::move(o));
  for (EvalObject& o : *unknown) o.role = EvalRole::kUnknown, objects.push_back(std::move(o));
  EvalParams p = reduced_params();
  p.methods = {MethodId::kFusion};
  p.stages = {{StageKind::kFull, 0}, {StageKind::kFraction, 0.2}};
  p.explore_max_keypoints = 0;
  p.stream_chunk_fraction = 0;
  p.seed = 42;
  p.train_conditions = default_training_sensors();  // the recipe's training views
  auto r = run_evaluation(objects, p, "shrec -> psb, psb-other unknown");
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->unknown_categories.size(), 10u);
  const std::vector<OpenSetRow> rows = open_set_summary(r->decisions, p.stages, MethodId::kFusion, 10);
  ASSERT_EQ(rows.size(), 2u);
  for (const OpenSetRow& row : rows)
    std::cout << "shrec -> psb, psb-other unknown, " << row.stage << ": AUROC " << row.auroc << ", known accepted "
              << row.known_acceptance << " %, unknown accepted " << row.false_acceptance << " %, right and accepted "
              << row.known_accuracy_open << " % (closest " << row.known_accuracy_closed << " %)\n";
  // 10 SHREC objects per category -> 8 PSB objects per category (6 parts) and 4 of each psb-other class,
  // 3 views, 3000 points, seed 42: 114 known views (one is 0.9 points) and 120 unknown ones a stage.
  // Measured: AUROC 0.900 (full) and 0.876 (20 %); at the default operating point 94.7 % of PSB's known
  // full views accepted, 94.7 % right and accepted (99.1 % closest), 48.3 % of the unknown ones accepted.
  EXPECT_GE(rows[0].auroc, 0.89);
  EXPECT_GE(rows[1].auroc, 0.865);
  EXPECT_GE(rows[0].known_acceptance, 93.5);
  EXPECT_GE(rows[0].known_accuracy_open, 93.5);
  EXPECT_LE(rows[0].false_acceptance, 50.0);
}

}  // namespace
}  // namespace glimpse

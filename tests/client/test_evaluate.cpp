// glimpse evaluate's pure parts: stages, the stage cut (the lab's), batch ranges within the limits,
// and the report's numbers (core's metrics) in text and JSON.
#include <gtest/gtest.h>

#include "client/batch_client.h"
#include "client/evaluate.h"
#include "glimpse/views/exploration.h"

namespace glimpse::client {
namespace {

TEST(Evaluate, ParseStages) {
  auto s = ParseStages("full, 10,20%");
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_EQ(s->size(), 3u);
  EXPECT_EQ((*s)[0].kind, StageKind::kFull);
  EXPECT_EQ((*s)[1], (Stage{StageKind::kFraction, 0.10}));
  EXPECT_EQ(stage_name((*s)[2]), "20%");
  EXPECT_EQ(ParseStages("full,full")->size(), 1u);
  for (const char* bad : {"", "10kp", "0", "150", "half"}) EXPECT_FALSE(ParseStages(bad).ok()) << bad;
}

TEST(Evaluate, StageCloudIsTheTopOfTheViewAsTheLabCutsIt) {
  Cloud view;
  for (int i = 0; i < 100; ++i) view.points.emplace_back(0.f, 0.f, float(i));
  view.sensor = Vec3(1, 2, 3);
  EXPECT_EQ(StageCloud(view, 400, {StageKind::kFull, 0}).points.size(), 100u);
  const Cloud top = StageCloud(view, 400, {StageKind::kFraction, 0.10});  // 10 % of the object's 400 points
  ASSERT_EQ(top.points.size(), 40u);
  EXPECT_EQ(top.points.front().z(), 99.f);
  EXPECT_EQ(top.points.back().z(), 60.f);
  EXPECT_EQ(top.sensor, view.sensor);
  EXPECT_EQ(top.points, reveal_top_down(view, fraction_prefix(100, 400, 0.10)).points);
}

TEST(Evaluate, BatchRangesKeepEveryCallWithinTheLimits) {
  const std::vector<size_t> sizes = {10, 10, 10, 50, 5, 200, 1};
  const auto r = BatchRanges(sizes, {3, 60});
  const std::vector<std::pair<size_t, size_t>> expected = {{0, 3}, {3, 5}, {5, 6}, {6, 7}};
  EXPECT_EQ(r, expected);  // the 200-point cloud alone: the server will say it is too large
  EXPECT_TRUE(BatchRanges({}, {}).empty());
}

EvaluationReport SmallReport() {
  EvaluationReport r;
  r.folder = "psb";
  r.model = "shrec:2";
  r.method = "fusion";
  r.categories = ReportCategories({"chair", "human"}, {"human", "chair", "lamp"});
  r.model_categories = 2;
  r.objects = {"chair/1", "human/2", "lamp/3"};
  r.object_truth = {0, 1, 2};
  r.views_per_object = 2;
  r.stages = {{StageKind::kFull, 0}};
  auto add = [&](int object, int view, int winner) {
    StageDecision d;
    d.object = object;
    d.view = view;
    d.stage = "full";
    d.truth = r.object_truth[size_t(object)];
    d.winner = winner;
    d.scores = {0.3, 0.7, 0.0};
    if (winner == 0) d.scores = {0.8, 0.2, 0.0};
    r.decisions.push_back(d);
  };
  add(0, 0, 0), add(0, 1, 1), add(1, 0, 1), add(1, 1, 1), add(2, 0, 0), add(2, 1, -1);
  r.failures.push_back({2, 1, "full", "INVALID_ARGUMENT", "too few points"});
  return r;
}

TEST(Evaluate, ReportCategoriesAreTheModelsThenTheFoldersOthers) {
  EXPECT_EQ(ReportCategories({"b", "a"}, {"c", "a", "d"}), (std::vector<std::string>{"b", "a", "c", "d"}));
}

TEST(Evaluate, TextReportHasAccuracyConfusionAndTheMisclassified) {
  const std::string text = EvaluationText(SmallReport());
  EXPECT_NE(text.find("model shrec:2, method fusion: 3 objects of psb, 2 views each (6 views)"), std::string::npos) << text;
  // 3 of 6 right; balanced: chair 50 %, human 100 %, lamp 0 % -> 50 %.
  EXPECT_NE(text.find("full   50.0 %    50.0 %    3/6"), std::string::npos) << text;
  EXPECT_NE(text.find("note: the model does not know 'lamp'"), std::string::npos);
  EXPECT_NE(text.find("chair  50.0   50.0"), std::string::npos) << text;
  EXPECT_NE(text.find("misclassified at full: 3 views of 2 objects"), std::string::npos);
  EXPECT_NE(text.find("chair/1  view 1 -> human (0.70)"), std::string::npos) << text;
  EXPECT_NE(text.find("lamp/3   view 0 -> chair (0.80), view 1 -> no answer"), std::string::npos) << text;
  EXPECT_NE(text.find("lamp/3 view 1 at full: INVALID_ARGUMENT: too few points"), std::string::npos);
}

// Answers with probabilities give each stage its calibration error; without them, none ("-", null).
TEST(Evaluate, ReportsTheCalibrationErrorOfTheProbabilities) {
  EvaluationReport r = SmallReport();
  EXPECT_NE(EvaluationJson(r).find("\"calibration_error\":null"), std::string::npos);
  // Known views: chair/1 right at 0.9 and wrong at 0.6 (human); human/2 right at 0.9 twice. Bins 0.9:
  // 3 views, 3 right, mean 0.9 -> 0.3 / 4; bin 0.6: 1 view, 0 right -> 0.6 / 4. ECE 0.225.
  const std::vector<std::vector<double>> p = {{0.9, 0.1}, {0.4, 0.6}, {0.1, 0.9}, {0.1, 0.9}};
  for (size_t i = 0; i < p.size(); ++i) r.decisions[i].probabilities = p[i];
  const std::string text = EvaluationText(r);
  EXPECT_NE(text.find("3/6          0.225"), std::string::npos) << text;
  EXPECT_NE(EvaluationJson(r).find("\"calibration_error\":0.225"), std::string::npos) << EvaluationJson(r);
}

TEST(Evaluate, JsonReportCarriesTheSameNumbers) {
  const std::string json = EvaluationJson(SmallReport());
  EXPECT_EQ(json.front(), '{');
  EXPECT_EQ(json.back(), '}');
  EXPECT_NE(json.find("\"stage\":\"full\",\"accuracy\":50,\"balanced_accuracy\":50,\"correct\":3,\"total\":6"),
            std::string::npos) << json;
  EXPECT_NE(json.find("\"human\":{\"chair\":0,\"human\":100}"), std::string::npos) << json;
  EXPECT_NE(json.find("{\"object\":\"lamp/3\",\"view\":1,\"stage\":\"full\",\"truth\":\"lamp\",\"winner\":null}"),
            std::string::npos) << json;
  EXPECT_NE(json.find("\"failures\":[{\"object\":\"lamp/3\",\"view\":1"), std::string::npos);
}

}  // namespace
}  // namespace glimpse::client

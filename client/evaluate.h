// `glimpse evaluate`'s pure parts: the stages asked for, the cloud of a view at a stage (a top-down
// prefix, as glimpse-lab cuts it), and the report (accuracy, balanced accuracy, confusion table and
// misclassified objects, computed with core's evaluation metrics) as text or JSON. No I/O here.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "glimpse/learning/metrics.h"
#include "glimpse/views/exploration.h"

namespace glimpse::client {

// "full,10,20" -> full, 10 %, 20 % (of the object's full cloud, revealed top-down); "10%" also reads.
// Keypoint stages ("10kp") need the server's keypoints and are refused here.
Expected<std::vector<Stage>> ParseStages(std::string_view text);

// The view cut at the stage: the whole view, or its top-down prefix holding fraction x full_points
// points (core's fraction_prefix + reveal_top_down, as glimpse-lab cuts it).
Cloud StageCloud(const Cloud& view, size_t full_points, const Stage& stage);

struct EvaluationReport {
  std::string folder;
  std::string model;      // "name:version"
  std::string method;     // "fusion"
  MethodId method_id = MethodId::kFusion;
  std::vector<std::string> categories;  // the model's, then the folder's categories the model lacks
  size_t model_categories = 0;          // the first ones are the model's
  std::vector<std::string> objects;     // "category/id"
  std::vector<int> object_truth;        // index into categories
  size_t views_per_object = 0;
  std::vector<Stage> stages;
  std::vector<StageDecision> decisions;  // core's, one per view and stage; winner -1: no answer
  struct Failure {
    int object = 0, view = -1;  // view -1: the whole object (its mesh did not load)
    std::string stage, code, message;
  };
  std::vector<Failure> failures;
  double seconds = 0;
};

// The report's categories: the model's in its order, then the folder's others, sorted.
std::vector<std::string> ReportCategories(const std::vector<std::string>& model_categories,
                                          const std::vector<std::string>& folder_categories);

std::string EvaluationText(const EvaluationReport& report);
std::string EvaluationJson(const EvaluationReport& report);

}  // namespace glimpse::client

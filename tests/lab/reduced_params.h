// The reduced evaluation the end-to-end tests vary: the zoo or a few objects of a collection, 2 folds,
// 3 views of 3000 points, BoK, VFH and the fusion.
#pragma once

#include "glimpse/lab/evaluation.h"

namespace glimpse::testing {

inline EvalParams reduced_params() {
  EvalParams p;
  p.points_per_object = 3000;
  p.views_per_object = 3;
  p.folds = 2;
  p.methods = {MethodId::kBoK, MethodId::kVFH, MethodId::kFusion};
  p.explore_step = 25;
  p.seed = 7;
  return p;
}

}  // namespace glimpse::testing

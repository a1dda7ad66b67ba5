// Hand-made decisions of test views, for tests of the metrics over them.
#pragma once

#include <string>
#include <utility>

#include "glimpse/learning/metrics.h"

namespace glimpse::testing {

inline StageDecision decision(std::string stage, MethodId m, int truth, int winner, int object = 0,
                              double visible = 0.3) {
  StageDecision d;
  d.stage = std::move(stage);
  d.method = m;
  d.truth = truth;
  d.winner = winner;
  d.object = object;
  d.visible_fraction = visible;
  return d;
}

}  // namespace glimpse::testing

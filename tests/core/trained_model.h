// The synthetic problem's small model (balls, boxes and cans; 18 training views, small codebooks), trained
// once per test binary, and 24 test views of 12 unseen objects.
#pragma once

#include <vector>

#include "glimpse/learning/model.h"
#include "glimpse/learning/train_params.h"
#include "synthetic.h"

namespace glimpse::test {

struct Trained {
  Model model;
  std::vector<TrainingCloud> test;
};

inline const Trained& trained() {
  static const Trained t = [] {
    auto m = train(synthetic_views(6, 3, 1), small_params());
    EXPECT_TRUE(m.ok()) << m.error().message;
    return Trained{m.ok() ? *m : Model{}, synthetic_views(4, 2, 2)};
  }();
  return t;
}

}  // namespace glimpse::test

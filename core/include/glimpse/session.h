// ScanSession: a remote scanner streams an object piece by piece; the session fuses the chunks,
// updates features incrementally and answers each chunk with an evolving Decision (sec. 4).
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/model.h"

namespace glimpse {

struct SessionParams {
  std::optional<Method> method;      // default: the model's default method
  size_t max_points = 1'000'000;     // accumulated (after duplicate removal)
  size_t max_chunks = 10'000;
  size_t max_chunk_points = 200'000;
};

struct Decision {
  size_t chunk_index = 0;           // 0-based index of the chunk this answers
  size_t points = 0;                // accumulated, after duplicate removal
  size_t keypoints = 0;
  std::vector<std::string> categories;
  std::vector<double> scores;       // one per category, in [0, 1]
  int winner = -1;                  // -1 while there is nothing to decide on
  int category_changes = 0;         // how often the winner changed so far
  int winner_held_chunks = 0;       // consecutive chunks the current winner has held
  bool settled = false;
  double confidence = 0;            // in [0, 1]
};

class ScanSession {
 public:
  static Expected<std::unique_ptr<ScanSession>> create(std::shared_ptr<const Model> model,
                                                       const SessionParams& params = {});
  virtual ~ScanSession() = default;
  // Adds a chunk (points in the session's common frame) and returns the updated decision.
  virtual Expected<Decision> add(const Cloud& chunk) = 0;
  virtual const Decision& last() const = 0;
};

}  // namespace glimpse

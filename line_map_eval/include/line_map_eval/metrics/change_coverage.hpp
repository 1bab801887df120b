// How a map follows a building that changed between two sessions (ROS-free): the true faces of the
// world before and after are cut into what was removed, what was added and what stayed, each over its
// parts the scans saw, and the map is scored on each: the share of the removed faces it no longer
// covers, and its ground-truth coverage of the added and of the unchanged ones.
#pragma once

#include <vector>

#include "line_map_eval/metrics/ground_truth_metrics.hpp"
#include "line_map_eval/simulation/ground_truth.hpp"
#include "linemap/geometry.hpp"

namespace line_map_eval
{
/// Pieces of true faces (free side on the left, as the faces), each seen.
struct ChangePieces
{
  std::vector<linemap::Segment2> removed;    ///< of the faces before, where no face after lies
  std::vector<linemap::Segment2> added;      ///< of the faces after, where no face before lay
  std::vector<linemap::Segment2> unchanged;  ///< of the faces after, where a face before lay
};

/// Splits the faces: a piece of a face lies where a face of the other world does when that face runs the same
/// way along the same line (within `tolerance` [m]) over it. Each piece is clipped to the parts of its face
/// seen (seenPartsOf) in its own world's truth; pieces shorter than `min_length` are dropped.
ChangePieces changePieces(const GroundTruth& before, const GroundTruth& after,
                          const GroundTruthParams& params, double tolerance = 0.01, double min_length = 0.2);

struct ChangeScores
{
  double removed_length = 0.0, added_length = 0.0, unchanged_length = 0.0;  ///< [m] of seen pieces
  double removed_retired = 0.0;     ///< [%] of the removed pieces' length no map segment covers
  double added_coverage = 0.0;      ///< [%] ground-truth coverage of the added pieces
  double unchanged_coverage = 0.0;  ///< [%] ground-truth coverage of the unchanged pieces
};

/// Scores `map` on `pieces` (evaluateAgainstGroundTruth over each set, every piece seen in full).
ChangeScores scoreChanges(const ChangePieces& pieces, const std::vector<linemap::Segment2>& map,
                          const GroundTruthParams& params);

}  // namespace line_map_eval

// The per-scan pipeline: preprocess -> (optional) breakpoint clustering ->
// algorithm on each point range -> collinear merge -> minimum size filters.
#pragma once

#include <memory>
#include <vector>

#include "line_extraction/breakpoint_clustering.hpp"
#include "line_extraction/collinear_merge.hpp"
#include "line_extraction/extractor.hpp"
#include "line_extraction/preprocess.hpp"
#include "line_extraction/sensor_model.hpp"
#include "linemap/params.hpp"

namespace line_extraction
{
/// Pipeline parameters (keys without a block, as at the top of config/line_extraction.yaml).
struct PipelineParams
{
  std::string algorithm = "srg";
  bool clustering = false;    ///< split the scan at breakpoints before the algorithm
  double range_sigma = 0.01;  ///< point noise for covariances and breakpoints [m]
  double max_usable_range = 30.0;
  BreakpointParams breakpoint;
  /// Range noise and point spacing behind the algorithms' distance thresholds ("thresholds":
  /// adaptive, or the papers' fixed values).
  SensorModel sensor;
  bool remove_isolated = false;  ///< drop lone readings between two neighbours of one surface
  bool merge = true;
  /// Merge gate 2.77, largest bridged gap 0.5 m (a doorway stays open).
  CollinearMergeParams merge_params{2.77, 0.01, 0.5};
  int min_points = 5;  ///< per output segment
  /// Per output segment [m]: at 1 cm range noise a shorter segment's direction is uncertain by
  /// more than 0.3 rad. Whatever it is set to, a segment no longer than kDegenerateSigmas *
  /// range_sigma (its points within the noise of one spot) is no line and never emitted.
  double min_length = 0.05;
  static constexpr double kDegenerateSigmas = 3.0;

  /// Reads and checks every pipeline key; throws linemap::ParameterError naming a bad one.
  static PipelineParams fromParams(const linemap::ParamSet& params);
};

/// The project's orientation convention: a segment runs so that the free side, where the sensor
/// is, lies on its left (the sensor at the laser frame's origin). Swaps start and end when needed;
/// the Hessian form does not depend on the direction. Scan order (counter-clockwise beams) already
/// gives it; fits whose members come out of order (Hough, RANSAC, EM, full-circle wraps) may not.
void orientFreeSideLeft(Segment& segment);

class LineExtractor
{
 public:
  /// Throws linemap::ParameterError naming a bad parameter or unknown algorithm.
  explicit LineExtractor(const linemap::ParamSet& params);

  /// Extracts the segments of one scan; throws ScanError naming a field of an
  /// unusable scan. The result (and preparedScan()) stay valid until the next call.
  const ExtractionResult& extract(const ScanInput& scan);

  const PreparedScan& preparedScan() const { return prepared_; }
  /// What the last extract() returned.
  const ExtractionResult& lastResult() const { return result_; }
  /// The same, for a caller appending segments found elsewhere (the submap's) before publishing.
  ExtractionResult& mutableResult() { return result_; }
  const PipelineParams& params() const { return params_; }
  const Extractor& algorithm() const { return *algorithm_; }

 private:
  PipelineParams params_;
  std::unique_ptr<Extractor> algorithm_;
  Preprocessor preprocessor_;
  CollinearMerger merger_;
  PreparedScan prepared_;
  std::vector<PointRange> clusters_;
  ExtractionResult raw_, merged_, result_;
};

}  // namespace line_extraction

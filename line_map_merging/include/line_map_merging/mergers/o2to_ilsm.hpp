// O2TO-ILSM: OTO-ILSM replayed frame by frame over all keyframes at their final (optimised) poses.
// Offline: the keyframes are stored and the map is built when it is asked for.
#pragma once

#include <memory>

#include "line_map_merging/mergers/fusion.hpp"
#include "line_map_merging/mergers/offline_merger.hpp"

namespace line_map_merging
{
class O2toIlsm : public OfflineMerger
{
 public:
  /// Throws linemap::ParameterError for invalid fusion thresholds.
  explicit O2toIlsm(const FusionParams& params = FusionParams());
  const char* name() const override { return "o2to"; }
  const FusionParams& params() const { return params_; }

 protected:
  std::vector<MapSegment> compute() const override;

 private:
  FusionParams params_;
};

}  // namespace line_map_merging

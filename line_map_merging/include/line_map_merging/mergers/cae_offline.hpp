// CAE-RLSM run offline: OTM-ILSM replayed frame by frame over all keyframes at their final poses
// (no map adjustment needed). Keeps the replayed merger, so the provenance can be queried.
#pragma once

#include <memory>

#include "line_map_merging/mergers/cae_rlsm.hpp"
#include "line_map_merging/mergers/offline_merger.hpp"

namespace line_map_merging
{
class CaeOffline : public OfflineMerger
{
 public:
  /// Throws linemap::ParameterError for invalid fusion thresholds.
  explicit CaeOffline(const CaeParams& params = CaeParams());
  const char* name() const override { return "cae_offline"; }
  std::vector<Leaf> leaves(std::uint64_t id) const override;
  bool hasProvenance() const override { return true; }
  const CaeParams& params() const { return params_; }

 protected:
  std::vector<MapSegment> compute() const override;
  void invalidate() const override { replay_.reset(); }

 private:
  CaeParams params_;
  mutable std::unique_ptr<CaeRlsm> replay_;  // the merger behind the cached map
};

}  // namespace line_map_merging

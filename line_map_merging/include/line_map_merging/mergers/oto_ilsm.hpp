// OTO-ILSM: online one-to-one incremental line segment merging (Kuo et al.), the baseline that
// CAE-RLSM's one-to-many merging improves on. Each new segment is fused with the single closest
// map segment meeting the fusion conditions (smallest vertical distance, ties broken by heading
// deviation, then by the smaller id), so a segment bridging two map segments leaves them apart.
// No provenance: the map cannot follow a loop closure (adjust() moves nothing).
#pragma once

#include <boost/geometry.hpp>
#include <boost/geometry/index/rtree.hpp>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "line_map_merging/mergers/fusion.hpp"
#include "line_map_merging/mergers/merger.hpp"

namespace line_map_merging
{
class OtoIlsm : public Merger
{
 public:
  /// Throws linemap::ParameterError for invalid fusion thresholds.
  explicit OtoIlsm(const FusionParams& params = FusionParams());

  const char* name() const override { return "oto"; }
  AddResult addKeyframe(const Keyframe& keyframe) override;
  AddResult addOriginals(std::uint64_t keyframe, const std::vector<linemap::Segment2>& segments) override;
  /// Without provenance nothing can be moved: counts the unknown indices, moved == 0.
  AdjustResult adjust(const std::vector<std::pair<std::uint64_t, linemap::Pose2>>& poses) override;
  std::vector<MapSegment> map() const override;
  std::vector<KeyframeInfo> keyframes() const override;
  std::size_t keyframeCount() const override { return keyframes_.size(); }
  std::size_t leafCount() const override { return leaf_count_; }
  std::size_t segmentCount() const override { return nodes_.size(); }
  void reset() override;
  std::unique_ptr<Merger> clone() const override { return std::make_unique<OtoIlsm>(*this); }

  const FusionParams& params() const { return params_; }

 private:
  using Point = boost::geometry::model::point<double, 2, boost::geometry::cs::cartesian>;
  using Box = boost::geometry::model::box<Point>;
  using Entry = std::pair<Box, std::uint64_t>;
  using RTree = boost::geometry::index::rtree<Entry, boost::geometry::index::quadratic<16>>;

  struct Node
  {
    Segment2 segment;
    FusionMoments moments;
    std::uint32_t count = 0;
    Box box;  // padded, as stored in the index
  };

  void insertSegment(const Segment2& world);

  FusionParams params_;
  std::vector<KeyframeInfo> keyframes_;
  std::unordered_map<std::uint64_t, std::size_t> slot_of_;
  std::unordered_map<std::uint64_t, Node> nodes_;
  RTree index_;
  std::uint64_t next_id_ = 0;
  std::size_t leaf_count_ = 0;
  std::vector<Entry> hits_;  // scratch
};

}  // namespace line_map_merging

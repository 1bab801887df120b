// The R-tree of map segments' bounding boxes the metrics search (boost::geometry).
#pragma once

#include <boost/geometry.hpp>
#include <boost/geometry/index/rtree.hpp>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "linemap/geometry.hpp"

namespace line_map_eval
{
using SegmentPoint = boost::geometry::model::point<double, 2, boost::geometry::cs::cartesian>;
using SegmentBox = boost::geometry::model::box<SegmentPoint>;
/// A box and the index of its segment.
using SegmentEntry = std::pair<SegmentBox, std::size_t>;
using SegmentTree = boost::geometry::index::rtree<SegmentEntry, boost::geometry::index::quadratic<16>>;

/// The segment's bounding box grown by `pad` on every side.
SegmentBox segmentBox(const linemap::Segment2& s, double pad = 0.0);

/// The boxes of the map segments grown by `pad`, in map order; throws std::invalid_argument
/// ("<what>: map segment j has non-finite coordinates") on a segment with a non-finite end.
std::vector<SegmentEntry> segmentBoxes(const std::vector<linemap::Segment2>& map, double pad,
                                       const std::string& what);

/// segmentBoxes() packed into an R-tree.
SegmentTree segmentTree(const std::vector<linemap::Segment2>& map, double pad, const std::string& what);

}  // namespace line_map_eval

// Every merger on the simulated office floor: segments extracted from the simulated scans, keyframes
// at the TRUE laser poses. Each map must have about as many segments as there are wall faces in sight
// (within 25 %) and no segment farther than 0.1 m from a true wall.
//
// Faces in sight, from the ground truth (the faces of the 10 cm walls, and both directions of the thin
// furniture outlines): true faces that continue each other on one line across a gap below kJoinGap
// are chained (the faces of two rooms on either side of a 10 cm partition, which the fusion conditions
// bridge); each keyframe's visible pieces are projected onto their chain, per side the laser is on, and
// the pieces are united where they overlap or leave a gap below kJoinGap. A perfect merger produces one
// segment per united run and side; the undirected methods (MS-RLSM, Li 2023) one per run over both
// sides. Runs shorter than the extractor's minimum segment length are not counted.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>
#include <string>
#include <utility>

#include "line_extraction/line_extractor.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/simulation/simulator.hpp"
#include "line_map_merging/mergers/merger.hpp"

namespace
{
using line_map_merging::Keyframe;
using linemap::Segment2;
using linemap::Vec2;

constexpr std::size_t kScans = 600;  // over one lap (one every ~0.25 m or ~0.2 rad)
constexpr std::size_t kEvery = 2;    // every 2nd scan becomes a keyframe
constexpr double kJoinGap = 0.2;     // [m] twice the fusion conditions' largest bridged gap
constexpr double kMinRun = 0.6;      // [m] srg's minimum segment length (config/line_extraction.yaml)

struct Office
{
  std::vector<Keyframe> keyframes;
  std::vector<Segment2> chains;  // true walls, collinear touching ones joined
  std::size_t faces_directed = 0;
  std::size_t faces_undirected = 0;
  std::size_t faces = 0;  // true faces of the world
};

/// Joins walls that lie on one line and overlap or leave a gap below kJoinGap; chain_of[i] = chain of wall i.
std::vector<Segment2> chainWalls(const std::vector<Segment2>& walls, std::vector<std::size_t>& chain_of)
{
  std::vector<std::size_t> parent(walls.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::size_t i)
  {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (std::size_t i = 0; i < walls.size(); ++i)
    for (std::size_t j = i + 1; j < walls.size(); ++j)
    {
      const Segment2 &a = walls[i], &b = walls[j];
      if (linemap::distanceToLine(b.start, a.start, a.end) > 1e-9 ||
          linemap::distanceToLine(b.end, a.start, a.end) > 1e-9)
        continue;
      const Vec2 u = (a.end - a.start).normalized();
      const double b0 = u.dot(b.start - a.start), b1 = u.dot(b.end - a.start);
      if (std::min(std::max(b0, b1), a.length()) - std::max(std::min(b0, b1), 0.0) > -kJoinGap)
        parent[find(i)] = find(j);
    }
  std::map<std::size_t, std::size_t> index_of_root;
  std::vector<std::vector<std::size_t>> members;
  chain_of.assign(walls.size(), 0);
  for (std::size_t i = 0; i < walls.size(); ++i)
  {
    auto it = index_of_root.emplace(find(i), members.size()).first;
    if (it->second == members.size()) members.emplace_back();
    members[it->second].push_back(i);
    chain_of[i] = it->second;
  }
  std::vector<Segment2> chains;
  for (const auto& m : members)
  {
    const Segment2& first = walls[m.front()];
    const Vec2 u = (first.end - first.start).normalized();
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::size_t i : m)
      for (const Vec2& p : {walls[i].start, walls[i].end})
      {
        lo = std::min(lo, u.dot(p - first.start));
        hi = std::max(hi, u.dot(p - first.start));
      }
    chains.emplace_back(first.start + lo * u, first.start + hi * u);
  }
  return chains;
}

/// Runs of length >= kMinRun after uniting intervals that overlap or leave a gap < kJoinGap.
std::size_t countRuns(std::vector<std::pair<double, double>> intervals)
{
  std::sort(intervals.begin(), intervals.end());
  std::size_t runs = 0;
  for (std::size_t i = 0; i < intervals.size();)
  {
    double lo = intervals[i].first, hi = intervals[i].second;
    for (++i; i < intervals.size() && intervals[i].first - hi < kJoinGap; ++i)
      hi = std::max(hi, intervals[i].second);
    runs += hi - lo >= kMinRun;
  }
  return runs;
}

const Office& office()
{
  static const Office data = []
  {
    Office o;
    line_map_eval::SimulationOptions options;
    options.scans = kScans;
    const auto sim = line_map_eval::simulate(
        line_map_eval::loadWorld(std::string(LINEMAP_SOURCE_DIR) + "/config/worlds/office.yaml"), options);
    std::vector<std::size_t> chain_of;
    o.chains = chainWalls(sim.truth.walls, chain_of);
    o.faces = sim.truth.walls.size();
    // Visible intervals along each chain: [chain][side].
    std::vector<std::vector<std::pair<double, double>>> seen[2];
    seen[0].resize(o.chains.size());
    seen[1].resize(o.chains.size());

    line_extraction::LineExtractor extractor{linemap::ParamSet()};
    const auto& g = sim.recording.geometry;
    for (std::size_t i = 0; i < sim.recording.scans.size(); i += kEvery)
    {
      const auto& ranges = sim.recording.scans[i].ranges;
      const line_extraction::ScanInput input = line_map_eval::scanInput(g, ranges);
      Keyframe k;
      k.index = i;
      k.stamp = sim.recording.scans[i].stamp;
      k.pose = sim.truth.scans[i].pose;  // true laser pose in the map
      k.mount = sim.recording.base_to_laser;
      for (const auto& s : extractor.extract(input).segments) k.segments.emplace_back(s.start, s.end);

      for (const auto& v : sim.truth.scans[i].visible)
      {
        const std::size_t c = chain_of[v.wall];
        const Segment2& chain = o.chains[c];
        const Vec2 u = (chain.end - chain.start).normalized();
        const Vec2 q = k.pose.translation() - chain.start;
        const int side = u.x() * q.y() - u.y() * q.x() > 0.0 ? 1 : 0;
        const double a = u.dot(v.segment.start - chain.start), b = u.dot(v.segment.end - chain.start);
        seen[side][c].emplace_back(std::min(a, b), std::max(a, b));
      }
      o.keyframes.push_back(std::move(k));
    }
    for (std::size_t c = 0; c < o.chains.size(); ++c)
    {
      o.faces_directed += countRuns(seen[0][c]) + countRuns(seen[1][c]);
      auto both = seen[0][c];
      both.insert(both.end(), seen[1][c].begin(), seen[1][c].end());
      o.faces_undirected += countRuns(both);
    }
    return o;
  }();
  return data;
}

/// max(endpoint distances) to the chained true wall that minimises it.
double distanceToNearestWall(const Segment2& s, const std::vector<Segment2>& walls)
{
  double best = std::numeric_limits<double>::infinity();
  for (const Segment2& w : walls)
    best = std::min(best, std::max(linemap::distanceToSegment(s.start, w.start, w.end),
                                   linemap::distanceToSegment(s.end, w.start, w.end)));
  return best;
}

bool undirected(const std::string& method)
{
  return method == "ms" || method == "li2023";
}

class MergerOnOffice : public ::testing::TestWithParam<std::string>
{
};
}  // namespace

TEST(MergersOffice, SimulationAndExtractionGiveAUsableInput)
{
  const Office& o = office();
  ASSERT_EQ(o.keyframes.size(), kScans / kEvery);
  std::size_t segments = 0;
  for (const Keyframe& k : o.keyframes) segments += k.segments.size();
  // A merger has something to merge: several views per wall in sight.
  EXPECT_GT(segments, 5 * o.faces_directed);
  // The 20 furniture sides of config/worlds/office.yaml are thin: each is two faces on one line, one
  // chain. The faces of the 10 cm walls are maximal straight pieces, so only those across a gap
  // below kJoinGap chain: the faces of neighbouring rooms beside a partition.
  EXPECT_LT(o.chains.size(), o.faces - 20);
  EXPECT_GT(o.faces_undirected, 30u);
  // Walls have two faces 10 cm apart, each its own line seen from one side: no chain is seen from
  // both sides (with infinitely thin walls every wall between two rooms was).
  EXPECT_EQ(o.faces_directed, o.faces_undirected);
}

TEST_P(MergerOnOffice, SegmentCountNearTheWallsInSightAndEverySegmentOnAWall)
{
  const Office& o = office();
  auto merger = line_map_merging::makeMerger(GetParam(), linemap::ParamSet());
  for (const Keyframe& k : o.keyframes) merger->addKeyframe(k);
  const auto map = merger->map();
  double worst = 0.0;
  for (const auto& m : map)
  {
    const double d = distanceToNearestWall(m.segment, o.chains);
    worst = std::max(worst, d);
    EXPECT_LE(d, 0.1) << "segment " << m.id << " (" << m.segment.start.transpose() << ") -> ("
                      << m.segment.end.transpose() << ") is " << d << " m from every wall";
  }
  const std::size_t faces = undirected(GetParam()) ? o.faces_undirected : o.faces_directed;
  std::printf("[ office   ] %-12s %4zu segments for %zu faces in sight, worst endpoint distance %.3f m\n",
              GetParam().c_str(), map.size(), faces, worst);
  const double walls = static_cast<double>(faces);
  EXPECT_GE(static_cast<double>(map.size()), 0.75 * walls);
  EXPECT_LE(static_cast<double>(map.size()), 1.25 * walls);
}

INSTANTIATE_TEST_SUITE_P(AllMergers, MergerOnOffice, ::testing::ValuesIn(line_map_merging::mergerNames()),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

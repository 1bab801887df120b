// The closures' acceptance alone, on a tight straight chain: a closure contradicting the chain by far
// more than its uncertainty allows is refused and leaves the graph as it was; one agreeing with it goes
// in without optimising; one off by a little goes in and the graph is optimised; a poor or ambiguous
// match is refused before the graph is looked at.
#include <gtest/gtest.h>

#include "graph_edges.hpp"
#include "line_map_merging/slam/closure_gate.hpp"
#include "slipped_chain.hpp"

using line_map_merging::ClosureGate;
using line_map_merging::ClosureOutcome;
using line_map_merging::ClosureVerdict;
using line_map_merging::LaserSlamParams;
using line_map_merging::LoopMatch;
using line_map_merging::MatchResult;
using line_map_merging::PoseGraph;
using line_map_merging::SlamCounters;
using linemap::Pose2;

namespace
{
constexpr std::size_t kLast = 10;

/// Nodes 0..10 a metre apart along x, chained by exact matched edges (2 cm, 0.002 rad).
PoseGraph chain(const LaserSlamParams& p)
{
  PoseGraph g(line_map_merging::PoseGraphParams{p.loop_loss_scale, 50});
  g.addNode(Pose2());
  for (std::size_t i = 1; i <= kLast; ++i)
  {
    g.addNode(Pose2(static_cast<double>(i), 0.0, 0.0));
    g.addEdge(graph_edges::edge(i - 1, i, Pose2(1.0, 0.0, 0.0), p.edge_sigma_xy, p.edge_sigma_theta));
  }
  return g;
}

/// A closure 0 -> kLast measuring `measurement`, as ConstraintBuilder would hand it over.
LoopMatch closure(const Pose2& measurement, const LaserSlamParams& p, double score = 0.9,
                  double ambiguity = 0.0)
{
  LoopMatch m;
  m.from = 0;
  m.to = kLast;
  MatchResult r;
  r.pose = measurement;
  r.score = score;
  m.match = r;
  m.ambiguity = ambiguity;
  m.edge.from = 0;
  m.edge.to = kLast;
  m.edge.measurement = measurement;
  m.edge.sigma_xy = p.loop_sigma_xy;
  m.edge.sigma_theta = p.loop_sigma_theta;
  m.edge.loop = true;
  return m;
}
}  // namespace

// 10 m of chain at 2 cm / 0.002 rad per metre and the closure's 5 cm: about 0.08 m along the chain, so
// 1 m is beyond any chi-square quantile one would use.
TEST(ClosureGate, RefusesAClosureContradictingATightChain)
{
  const LaserSlamParams p;
  PoseGraph g = chain(p);
  ClosureGate gate(p);
  SlamCounters counters;
  const ClosureVerdict v = gate.consider(closure(Pose2(kLast - 1.0, 0.0, 0.0), p), g, counters);
  EXPECT_FALSE(v.accepted);
  EXPECT_FALSE(v.optimized);
  EXPECT_EQ(g.edges().size(), kLast);
  EXPECT_EQ(g.node(kLast).x, static_cast<double>(kLast));
  EXPECT_EQ(counters.loops_inconsistent, 1u);
  EXPECT_EQ(counters.loops_accepted, 0u);
  ASSERT_EQ(gate.attempts().size(), 1u);
  EXPECT_EQ(gate.attempts()[0].outcome, ClosureOutcome::kInconsistent);
  EXPECT_EQ(gate.attempts()[0].from, 0u);
  EXPECT_EQ(gate.attempts()[0].to, kLast);
}

TEST(ClosureGate, AcceptsAnAgreeingClosureWithoutOptimising)
{
  const LaserSlamParams p;
  PoseGraph g = chain(p);
  ClosureGate gate(p);
  SlamCounters counters;
  const ClosureVerdict v = gate.consider(closure(Pose2(kLast, 0.0, 0.0), p), g, counters);
  EXPECT_TRUE(v.accepted);
  EXPECT_FALSE(v.optimized);
  ASSERT_EQ(g.edges().size(), kLast + 1);
  EXPECT_TRUE(g.edges().back().loop);
  EXPECT_EQ(counters.loops_accepted, 1u);
  EXPECT_EQ(counters.loops_consistent, 1u);
  EXPECT_EQ(counters.optimizations, 0u);
  EXPECT_EQ(gate.attempts().back().outcome, ClosureOutcome::kAccepted);
}

// 10 cm short of the chain: within the gate, beyond loop_consistent_xy. The optimised graph meets it
// part way (the chain's 10 edges together are about as certain as the closure).
TEST(ClosureGate, AcceptsADisagreeingClosureAndOptimises)
{
  const LaserSlamParams p;
  PoseGraph g = chain(p);
  ClosureGate gate(p);
  SlamCounters counters;
  const ClosureVerdict v = gate.consider(closure(Pose2(kLast - 0.1, 0.0, 0.0), p), g, counters);
  EXPECT_TRUE(v.accepted);
  EXPECT_TRUE(v.optimized);
  EXPECT_EQ(g.edges().size(), kLast + 1);
  EXPECT_EQ(counters.optimizations, 1u);
  EXPECT_EQ(counters.loops_accepted, 1u);
  EXPECT_LT(g.node(kLast).x, kLast - 0.01);
  EXPECT_GT(g.node(kLast).x, kLast - 0.1);
  EXPECT_EQ(gate.attempts().back().outcome, ClosureOutcome::kAccepted);
}

TEST(ClosureGate, RefusesPoorAndAmbiguousMatchesBeforeTheGraph)
{
  const LaserSlamParams p;
  PoseGraph g = chain(p);
  ClosureGate gate(p);
  SlamCounters counters;
  EXPECT_FALSE(gate.consider(closure(Pose2(kLast, 0.0, 0.0), p, p.loop_min_score / 2), g, counters).accepted);
  EXPECT_FALSE(gate.consider(closure(Pose2(kLast, 0.0, 0.0), p, 0.9, 1.0), g, counters).accepted);
  LoopMatch none;  // the search found nothing: an attempt, not recorded
  none.to = kLast;
  EXPECT_FALSE(gate.consider(none, g, counters).accepted);
  EXPECT_EQ(counters.loops_rejected_score, 2u);
  EXPECT_EQ(counters.loops_ambiguous, 1u);
  EXPECT_EQ(g.edges().size(), kLast);
  ASSERT_EQ(gate.attempts().size(), 2u);
  EXPECT_EQ(gate.attempts()[0].outcome, ClosureOutcome::kRejectedScore);
  EXPECT_EQ(gate.attempts()[1].outcome, ClosureOutcome::kAmbiguous);
}

namespace
{
/// The out-and-back drive's chain, its edge into node 35 slipped by 0.3 m and 5 degrees.
PoseGraph slippedChain(const LaserSlamParams& p)
{
  return slipped_chain::slippedChain(35, Pose2(0.1, 0.28, 5.0 * linemap::kPi / 180.0), p.edge_sigma_xy,
                                     p.edge_sigma_theta,
                                     line_map_merging::PoseGraphParams{p.loop_loss_scale, 50});
}

/// A closure j -> k measuring the true relative pose composed with `error`.
LoopMatch trueClosure(std::size_t j, std::size_t k, const LaserSlamParams& p, const Pose2& error = {})
{
  const auto truth = slipped_chain::outAndBack();
  LoopMatch m = closure(truth[j].inverse() * truth[k] * error, p);
  m.from = m.edge.from = j;
  m.to = m.edge.to = k;
  return m;
}
}  // namespace

// Three closures across the slip, from older keyframes two submap spans apart: each alone is refused (the
// chain claims the slipped estimate), the third makes a group that agrees with itself, and all three go in
// and pull the return leg back. Without the consensus (loop_consensus 0) the slip stays.
TEST(ClosureGate, IndependentClosuresAgreeingWithEachOtherOutvoteTheChain)
{
  LaserSlamParams p;
  const auto truth = slipped_chain::outAndBack();
  for (const std::size_t consensus : {std::size_t{0}, std::size_t{3}})
  {
    p.loop_consensus = consensus;
    PoseGraph g = slippedChain(p);
    ClosureGate gate(p);
    SlamCounters counters;
    ClosureVerdict last;
    for (const std::size_t j : {34u, 21u, 8u}) last = gate.consider(trueClosure(j, 79 - j, p), g, counters);
    // Node 71 beside node 8: where the closures say it is, relative to the start.
    const Pose2 there = g.node(0).inverse() * g.node(71);
    const double miss = std::hypot(there.x - truth[71].x, there.y - truth[71].y);
    if (consensus == 0)
    {
      EXPECT_FALSE(last.accepted);
      EXPECT_EQ(counters.loops_inconsistent, 3u);
      EXPECT_EQ(counters.inconsistent_in_a_row, 3u);
      EXPECT_GT(miss, 0.5);  // the slip swung the return leg by most of a metre
    }
    else
    {
      EXPECT_TRUE(last.accepted);
      EXPECT_TRUE(last.optimized);
      EXPECT_EQ(counters.loops_by_consensus, 3u);
      EXPECT_EQ(counters.loops_inconsistent, 0u);
      EXPECT_EQ(counters.inconsistent_in_a_row, 0u);
      EXPECT_EQ(counters.most_inconsistent_in_a_row, 3u);  // the third completed the group
      for (const auto& a : gate.attempts()) EXPECT_EQ(a.outcome, ClosureOutcome::kAccepted);
      EXPECT_LT(miss, 0.3);
    }
  }
}

// Closures against one submap share its errors: three that agree but come from neighbouring older keyframes
// are one vote, not three, and the chain stands.
TEST(ClosureGate, NeighbouringClosuresAreOneVote)
{
  LaserSlamParams p;
  PoseGraph g = slippedChain(p);
  ClosureGate gate(p);
  SlamCounters counters;
  ClosureVerdict last;
  for (const std::size_t j : {30u, 28u, 26u}) last = gate.consider(trueClosure(j, 79 - j, p), g, counters);
  EXPECT_FALSE(last.accepted);
  EXPECT_EQ(counters.loops_by_consensus, 0u);
  EXPECT_EQ(counters.loops_inconsistent, 3u);
}

// A match that slid along a direction it barely determines (a corridor's axis, weight 0.01: 0.5 m along
// it): its edge keeps the estimate there (heldToEstimate), so the edge alone agrees with the chain. The gate
// judges the match as found: slid 3 m against a chain known to about 0.06 m, it is refused (6 of its own
// standard deviations along the axis, beyond the 4 of the gate); slid 0.2 m it goes in, held.
TEST(ClosureGate, JudgesTheMatchAsFoundNotAsHeldToTheEstimate)
{
  const LaserSlamParams p;
  line_map_merging::TranslationShape corridor;
  corridor.weights << 0.01, 0.0, 0.0, 1.0;
  corridor.degenerate = true;
  const Pose2 estimate(kLast, 0.0, 0.0);
  const auto slid = [&](double along)
  {
    LoopMatch m = closure(Pose2(kLast - along, 0.0, 0.0), p);
    m.shape = corridor;
    m.edge.translation_weights = corridor.weights;
    m.edge.measurement = line_map_merging::heldToEstimate(m.match->pose, estimate, corridor);
    return m;
  };
  {
    PoseGraph g = chain(p);
    ClosureGate gate(p);
    SlamCounters counters;
    const LoopMatch far = slid(3.0);
    EXPECT_NEAR(far.edge.measurement.x, kLast - 0.03, 1e-12);
    EXPECT_FALSE(gate.consider(far, g, counters).accepted);
    EXPECT_EQ(counters.loops_inconsistent, 1u);
    EXPECT_EQ(g.edges().size(), kLast);
  }
  PoseGraph g = chain(p);
  ClosureGate gate(p);
  SlamCounters counters;
  EXPECT_TRUE(gate.consider(slid(0.2), g, counters).accepted);
  ASSERT_EQ(g.edges().size(), kLast + 1);
  EXPECT_NEAR(g.edges().back().measurement.x, kLast - 0.002, 1e-12);
  EXPECT_NEAR(g.node(kLast).x, kLast, 0.01);
}

// The score floor is loop_min_score, or loop_min_score_ratio times the front end's typical score where
// that is lower (hand-computed: 0.65 x 0.6 = 0.39); unknown (0) or a ratio of 0 leave loop_min_score.
TEST(ClosureGate, TheScoreFloorFollowsTheFrontEndsScoreDown)
{
  LaserSlamParams p;
  p.loop_min_score = 0.55;
  p.loop_min_score_ratio = 0.65;
  EXPECT_DOUBLE_EQ(p.loopMinScore(0.6), 0.39);
  EXPECT_DOUBLE_EQ(p.loopMinScore(0.95), 0.55);
  EXPECT_DOUBLE_EQ(p.loopMinScore(0.0), 0.55);
  LaserSlamParams off = p;
  off.loop_min_score_ratio = 0.0;
  EXPECT_DOUBLE_EQ(off.loopMinScore(0.6), 0.55);

  // A true closure scoring 0.45: refused against a front end scoring 0.95, accepted against one scoring 0.6.
  for (double front_end : {0.95, 0.6})
  {
    PoseGraph g = chain(p);
    ClosureGate gate(p);
    gate.setFrontEndScore(front_end);
    SlamCounters counters;
    const bool accepted = gate.consider(closure(Pose2(kLast, 0.0, 0.0), p, 0.45), g, counters).accepted;
    EXPECT_EQ(accepted, front_end < 0.7) << front_end;
    ASSERT_EQ(gate.attempts().size(), 1u);
    EXPECT_DOUBLE_EQ(gate.attempts()[0].min_score, front_end < 0.7 ? 0.39 : 0.55);
    EXPECT_EQ(counters.loops_rejected_score, accepted ? 0u : 1u);
  }
}

// The closures' acceptance alone, on a tight straight chain: a closure contradicting the chain by far
// more than its uncertainty allows is refused and leaves the graph as it was; one agreeing with it goes
// in without optimising; one off by a little goes in and the graph is optimised; a poor or ambiguous
// match is refused before the graph is looked at.
#include <gtest/gtest.h>

#include "line_map_merging/slam/closure_gate.hpp"

using line_map_merging::ClosureGate;
using line_map_merging::ClosureOutcome;
using line_map_merging::ClosureVerdict;
using line_map_merging::LaserSlamParams;
using line_map_merging::LoopMatch;
using line_map_merging::MatchResult;
using line_map_merging::PoseGraph;
using line_map_merging::PoseGraphEdge;
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
    PoseGraphEdge e;
    e.from = i - 1;
    e.to = i;
    e.measurement = Pose2(1.0, 0.0, 0.0);
    e.sigma_xy = p.edge_sigma_xy;
    e.sigma_theta = p.edge_sigma_theta;
    g.addEdge(e);
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

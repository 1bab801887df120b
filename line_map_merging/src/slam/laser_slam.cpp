#include "line_map_merging/slam/laser_slam.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "line_map_merging/slam/chain_edge.hpp"
#include "line_map_merging/slam/likelihood_grid.hpp"
#include "line_map_merging/slam/scan_matcher.hpp"
#include "linemap/small_helpers.hpp"

namespace line_map_merging
{
using linemap::Pose2;

namespace
{
PoseGraphParams graphParams(const LaserSlamParams& params)
{
  return {params.loop_loss_scale, 50};
}
}  // namespace

std::string closureSummary(const SlamCounters& c)
{
  std::ostringstream out;
  out << c.loops_accepted << " closures of " << c.loop_attempts
      << " attempts (refused: " << c.loops_rejected_score << " score, " << c.loops_ambiguous << " ambiguous, "
      << c.loops_inconsistent << " inconsistent, " << c.loops_rejected_graph << " graph, " << c.loops_pending
      << " uncorroborated; " << c.loops_by_consensus << " by consensus; most inconsistent in a row "
      << c.most_inconsistent_in_a_row << "; longest run held to the constant velocity " << std::fixed
      << std::setprecision(1) << c.longest_held_time << " s; " << c.suspect_edges
      << " chain edges disagreeing with the odometry, " << c.suspect_edges_on_odometry << " of them on it)";
  return out.str();
}

LaserSlam::LaserSlam(const LaserSlamParams& params)
    : params_(params),
      front_end_(params),
      constraints_(params),
      gate_(params),
      graph_(graphParams(params)),
      time_jumps_(params.time_jump_tolerance, {"scan"})
{
}

void LaserSlam::reset()
{
  front_end_ = LocalTrajectoryBuilder(params_);
  constraints_ = ConstraintBuilder(params_);
  gate_ = ClosureGate(params_);
  graph_.clear();
  keyframes_.clear();
  scans_.clear();
  recent_disagreements_.clear();
  time_jumps_.reset();
  continuation_.reset();
}

bool LaserSlam::observeStamp(double stamp)
{
  if (!time_jumps_.observe(0.0, stamp)) return false;
  ++counters_.time_jumps;
  return true;
}

bool LaserSlam::restartOnTimeJump(double stamp)
{
  // The check alone, on a copy: addScan records the stamp when the scan comes.
  linemap::TimeJumpDetector probe = time_jumps_;
  if (!probe.observe(0.0, stamp)) return false;
  ++counters_.time_jumps;
  ++counters_.new_trajectories;
  reset();
  return true;
}

SlamOutcome LaserSlam::addScan(const SlamScan& in)
{
  keyframe_added_ = graph_optimized_ = false;
  ++counters_.scans;
  observeStamp(in.stamp);
  const auto start = std::chrono::steady_clock::now();
  LocalScanResult local = front_end_.addScan(in, counters_);
  if (local.outcome == SlamOutcome::kRejected) return local.outcome;
  last_match_weights_ = local.match_weights;
  const std::size_t index = scans_.size();
  if (local.keyframe) addKeyframe(local, index);
  if (continuation_ && keyframes_.size() == continuation_->first_keyframe)
  {
    // A continued trajectory before its first keyframe: posed in the map frame by its start.
    scans_.push_back({local.scan.stamp, static_cast<std::size_t>(-1), continuation_->origin * local.pose});
  }
  else if (keyframes_.empty())
  {
    // No keyframe yet (the first scans were empty): nothing to hang the scan on.
    scans_.push_back({local.scan.stamp, static_cast<std::size_t>(-1), local.pose});
  }
  else
    scans_.push_back(
        {local.scan.stamp, keyframes_.size() - 1, keyframes_.back().local.inverse() * local.pose});
  counters_.last_match_ms = linemap::millisecondsSince(start);
  return local.outcome;
}

void LaserSlam::addKeyframe(LocalScanResult& scan, std::size_t scan_index)
{
  const bool chain_matched = scan.chain_matched;
  SlamKeyframe kf;
  kf.stamp = scan.scan.stamp;
  kf.scan = scan_index;
  kf.local = scan.pose;
  kf.points = scan.scan.points;
  kf.joins = std::move(scan.joins);
  kf.path = scan.path;
  if (keyframes_.empty())
    graph_.addNode(kf.local);
  else if (continuation_ && keyframes_.size() == continuation_->first_keyframe)
  {
    graph_.addNode(continuation_->origin * kf.local);
    anchorContinuation(keyframes_.size());
  }
  else
  {
    const Pose2 relative = keyframes_.back().local.inverse() * kf.local;
    const std::size_t prev = keyframes_.size() - 1;
    PoseGraphEdge e;
    e.from = prev;
    e.to = prev + 1;
    e.measurement = relative;
    e.sigma_xy = chain_matched ? params_.edge_sigma_xy : params_.odometry_sigma_xy;
    e.sigma_theta = chain_matched ? params_.edge_sigma_theta : params_.odometry_sigma_theta;
    // A match far from the odometry's motion over the same step is a suspected slip: its edge widens.
    bool suspect = false;
    if (chain_matched && scan.odometry_motion && params_.edge_odometry_disagreement)
      suspect = widenBySlip(scan.odometry_motion->inverse() * relative, e);
    if (suspect && params_.suspect_edge_follows_odometry &&
        odometryFitsBetter(keyframes_.back(), kf.points, relative, *scan.odometry_motion))
    {
      e.measurement = *scan.odometry_motion;
      ++counters_.suspect_edges_on_odometry;
    }
    if (chain_matched)
    {
      // What the keyframe's match determined: along a direction it left to the odometry, the edge is as
      // loose as an odometry edge, so a closure may move the keyframe there.
      e.translation_weights = chainEdgeTranslationWeights(last_match_weights_, keyframes_.back().local.theta,
                                                          params_.edge_sigma_xy, params_.odometry_sigma_xy);
    }
    graph_.addNode(graph_.node(prev) * e.measurement);
    graph_.addEdge(e);
  }
  keyframes_.push_back(std::move(kf));
  ++counters_.keyframes;
  keyframe_added_ = true;
  if (params_.loop_candidates > 0 && (keyframes_.size() - 1) % params_.loop_every == 0)
  {
    const auto start = std::chrono::steady_clock::now();
    closeLoops();
    counters_.total_loop_ms += linemap::millisecondsSince(start);
  }
}

void LaserSlam::anchorContinuation(std::size_t k)
{
  tieToNearestSaved(k, continuation_->first_keyframe, continuation_->sigma_xy, continuation_->sigma_theta);
}

void LaserSlam::tieToNearestSaved(std::size_t k, std::size_t saved, double sigma_xy, double sigma_theta)
{
  const linemap::Vec2 here = graph_.node(k).translation();
  std::size_t nearest = 0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t j = 0; j < saved; ++j)
  {
    const double d = (graph_.node(j).translation() - here).squaredNorm();
    if (d < best) best = d, nearest = j;
  }
  PoseGraphEdge e;
  e.from = nearest;
  e.to = k;
  e.measurement = graph_.node(nearest).inverse() * graph_.node(k);
  e.sigma_xy = sigma_xy;
  e.sigma_theta = sigma_theta;
  e.loop = true;
  graph_.addEdge(e);
}

bool LaserSlam::odometryFitsBetter(const SlamKeyframe& previous, const std::vector<linemap::Vec2>& points,
                                   const Pose2& matched, const Pose2& odometry) const
{
  // The two scans alone, in the previous keyframe's frame: the front end matched against a local map that
  // a slip carries along with it, so only the scan pair still shows where the new scan lies. It tells only
  // where the odometry's pose makes the pair fit: where the two scans share little (far apart, outdoors)
  // neither pose fits them, and the match is kept.
  const LikelihoodGrid previous_scan(previous.points, previous.joins, params_.resolution, params_.sigma, 0.5);
  const double on_odometry = matchScore(previous_scan, points, odometry);
  return on_odometry >= kPairFits && on_odometry > matchScore(previous_scan, points, matched);
}

bool LaserSlam::widenBySlip(const Pose2& disagreement, PoseGraphEdge& e)
{
  // The match against the odometry over the same step: two independent measurements of one motion. Their
  // usual disagreement is the odometry's noise (robust scale of the recent ones: the odometry's quality
  // is the run's, not a constant); one far beyond it is a slip of one of the two. The edge is then no
  // more certain than they agree, so closures across a slip of the front end put their correction there
  // instead of bending the whole chain (and a slip of the odometry costs little: closures hold the rest).
  const double shift = std::hypot(disagreement.x, disagreement.y);
  const double turn = std::fabs(linemap::normalizeAngle(disagreement.theta));
  constexpr std::size_t kHistory = 200, kShortHistory = 10;
  constexpr double kOutlier = 6.0;  // robust standard deviations: no noise of a working odometry reaches it
  // 1.4826 x the median absolute value: the standard deviation of a normal distribution. The edge's own
  // sigmas keep the scale above zero, and judge the first steps of a run before any history exists.
  double shift_scale = e.sigma_xy, turn_scale = e.sigma_theta;
  if (!recent_disagreements_.empty())
  {
    std::vector<double> shifts, turns;
    for (const auto& [s, t] : recent_disagreements_)
    {
      shifts.push_back(s);
      turns.push_back(t);
    }
    shift_scale += 1.4826 * linemap::median(shifts);
    turn_scale += 1.4826 * linemap::median(turns);
  }
  const bool suspect = shift > kOutlier * shift_scale || turn > kOutlier * turn_scale;
  if (suspect)
  {
    e.sigma_xy = std::hypot(e.sigma_xy, shift);
    e.sigma_theta = std::hypot(e.sigma_theta, turn);
    ++counters_.suspect_edges;
    constraints_.suspectEdge(e.to, shift, turn);
    // An outlier does not widen the noise it is judged by, once there is enough of it to judge by (until
    // then the median shrugs one off, and an odometry noisier than the edge's sigmas still gets its scale).
    if (recent_disagreements_.size() >= kShortHistory) return true;
  }
  recent_disagreements_.push_back({shift, turn});
  if (recent_disagreements_.size() > kHistory) recent_disagreements_.pop_front();
  return suspect;
}

void LaserSlam::closeLoops()
{
  const std::size_t k = keyframes_.size() - 1;
  const LoopSearch search = constraints_.search(keyframes_, graph_, k);
  gate_.setFrontEndScore(front_end_.runScore());
  for (std::size_t j : search.candidates)
  {
    // From the graph as the previous candidate's closure left it.
    const ClosureVerdict verdict =
        gate_.consider(constraints_.match(keyframes_, graph_, j, k, search, counters_), graph_, counters_);
    graph_optimized_ |= verdict.optimized;
    if (verdict.accepted) constraints_.closureAccepted(keyframes_[k].path, graph_);
  }
}

std::vector<std::pair<double, Pose2>> LaserSlam::trajectory() const
{
  std::vector<std::pair<double, Pose2>> out;
  out.reserve(keyframes_.size());
  for (std::size_t i = 0; i < keyframes_.size(); ++i) out.emplace_back(keyframes_[i].stamp, graph_.node(i));
  return out;
}

std::vector<std::pair<double, Pose2>> LaserSlam::scanPoses() const
{
  std::vector<std::pair<double, Pose2>> out;
  out.reserve(scans_.size());
  for (const auto& s : scans_)
  {
    if (s.keyframe < keyframes_.size())
      out.emplace_back(s.stamp, graph_.node(s.keyframe) * s.relative);
    else
      out.emplace_back(s.stamp, s.relative);
  }
  return out;
}

Pose2 LaserSlam::currentPose() const
{
  const Pose2& last_local = front_end_.currentLocal();
  if (continuation_ && keyframes_.size() == continuation_->first_keyframe)
    return continuation_->origin * last_local;
  if (keyframes_.empty()) return last_local;
  const std::size_t k = keyframes_.size() - 1;
  return graph_.node(k) * (keyframes_[k].local.inverse() * last_local);
}

double LaserSlam::unclosedShare() const
{
  if (keyframes_.size() < 2 || keyframes_.back().path <= 0.0) return 0.0;
  // Keyframe intervals spanned by a closure, merged.
  std::vector<std::pair<std::size_t, std::size_t>> spans;
  for (const auto& e : graph_.edges())
    if (e.loop) spans.push_back({std::min(e.from, e.to), std::max(e.from, e.to)});
  std::sort(spans.begin(), spans.end());
  double closed = 0.0;
  std::size_t start = 0, end = 0;
  bool open = false;
  auto flush = [&] { closed += keyframes_[end].path - keyframes_[start].path; };
  for (const auto& [a, b] : spans)
  {
    if (open && a <= end)
      end = std::max(end, b);
    else
    {
      if (open) flush();
      start = a;
      end = b;
      open = true;
    }
  }
  if (open) flush();
  return std::clamp(1.0 - closed / keyframes_.back().path, 0.0, 1.0);
}

std::string LaserSlam::trouble() const
{
  // More refusals in a row than a consensus needs several times over: the closures keep telling the
  // estimate it is wrong and nothing has outvoted it.
  const std::size_t many = std::max<std::size_t>(10, 3 * params_.loop_consensus);
  if (counters_.inconsistent_in_a_row < many) return {};
  return std::to_string(counters_.inconsistent_in_a_row) +
         " loop closures in a row refused as inconsistent with the trajectory: the front end may have "
         "slipped";
}

std::vector<std::pair<std::string, std::string>> LaserSlam::diagnostics() const
{
  const auto& c = counters_;
  auto n = [](std::size_t v) { return std::to_string(v); };
  auto fixed = [](double v)
  {
    std::ostringstream out;
    out.precision(3);
    out << std::fixed << v;
    return out.str();
  };
  std::ostringstream opt;
  opt.precision(3);
  opt << c.last_optimization_ms;
  std::ostringstream total;
  total.precision(4);
  total << c.total_optimization_ms;
  return {{"scans", n(c.scans)},
          {"matched scans", n(c.matched)},
          {"scans posed by odometry (barely moved)", n(c.filtered)},
          {"scans posed by prediction (not matched)", n(c.predicted)},
          {"scans with too few points", n(c.few_points)},
          {"poor matches", n(c.poor_matches)},
          {"scans without odometry", n(c.without_odometry)},
          {"odometry jumps", n(c.odometry_jumps)},
          {"wide searches (match off the odometry)", n(c.wide_searches)},
          {"scans out of order (ignored)", n(c.rejected)},
          {"time jumps back", n(c.time_jumps)},
          {"keyframes", n(c.keyframes)},
          {"loop closure attempts", n(c.loop_attempts)},
          {"loop closures accepted", n(c.loops_accepted)},
          {"loop closures consistent (not optimised)", n(c.loops_consistent)},
          {"loop closures waiting for corroboration", n(c.loops_pending)},
          {"loop closures rejected (ambiguous)", n(c.loops_ambiguous)},
          {"loop closures rejected (inconsistent with the graph)", n(c.loops_inconsistent)},
          {"loop closures accepted with a direction their match left open", n(c.loops_degenerate)},
          {"matches leaving a direction to the odometry", n(c.degenerate_matches)},
          {"loop closures rejected (score)", n(c.loops_rejected_score)},
          {"front end's recent mean match score", fixed(front_end_.runScore())},
          {"loop closures' score floor (now)", fixed(params_.loopMinScore(front_end_.runScore()))},
          {"loop closures rejected (graph)", n(c.loops_rejected_graph)},
          {"loop closures accepted by consensus (outvoting the chain)", n(c.loops_by_consensus)},
          {"loop closures refused as inconsistent in a row (now)", n(c.inconsistent_in_a_row)},
          {"loop closures refused as inconsistent in a row (most)", n(c.most_inconsistent_in_a_row)},
          {"front-end matches at the search window's border", n(c.border_matches)},
          {"longest run held to the constant velocity [s]", fixed(c.longest_held_time)},
          {"chain edges widened (disagreeing with the odometry)", n(c.suspect_edges)},
          {"of them on the odometry's motion (the scan pair fits it better)", n(c.suspect_edges_on_odometry)},
          {"share of the path no closure spans [%]",
           std::to_string(static_cast<int>(std::lround(100.0 * unclosedShare())))},
          {"optimizations", n(c.optimizations)},
          {"last optimization [ms]", opt.str()},
          {"total optimization [ms]", total.str()},
          {"scans dropped (no tf)", n(c.dropped)},
          {"scans stamped zero", n(c.zero_stamps)},
          {"new trajectories (time jumped back)", n(c.new_trajectories)},
          {"trajectories published", n(c.paths)}};
}

SlamSession LaserSlam::session() const
{
  SlamSession out;
  out.keyframes = keyframes_;
  out.nodes.reserve(graph_.nodeCount());
  for (std::size_t i = 0; i < graph_.nodeCount(); ++i) out.nodes.push_back(graph_.node(i));
  out.edges = graph_.edges();
  out.scans.reserve(scans_.size());
  for (const auto& s : scans_) out.scans.push_back({s.stamp, s.keyframe, s.relative});
  return out;
}

void LaserSlam::restore(const SlamSession& session)
{
  const std::size_t n = session.keyframes.size();
  if (session.nodes.size() != n)
    throw std::invalid_argument("session: " + std::to_string(session.nodes.size()) + " graph nodes for " +
                                std::to_string(n) + " keyframes");
  PoseGraph graph(graphParams(params_));
  for (const auto& node : session.nodes) graph.addNode(node);
  for (const auto& e : session.edges) graph.addEdge(e);  // throws on a node it does not have
  std::vector<ScanRecord> scans;
  scans.reserve(session.scans.size());
  for (const auto& s : session.scans)
  {
    if (s.keyframe != static_cast<std::size_t>(-1) && s.keyframe >= n)
      throw std::invalid_argument("session: a scan on keyframe " + std::to_string(s.keyframe) + " of " +
                                  std::to_string(n));
    scans.push_back({s.stamp, s.keyframe, s.relative});
  }
  reset();
  graph_ = std::move(graph);
  keyframes_ = session.keyframes;
  scans_ = std::move(scans);
  front_end_.resumeFrom(keyframes_);
  // The loop search's window from the newest keyframe a closure holds.
  std::size_t newest_closed = 0;
  for (const auto& e : graph_.edges())
    if (e.loop) newest_closed = std::max({newest_closed, e.from, e.to});
  if (!keyframes_.empty()) constraints_.closureAccepted(keyframes_[newest_closed].path, graph_);
}

void LaserSlam::continueFrom(const SlamSession& session, const Pose2& start, double sigma_xy,
                             double sigma_theta)
{
  if (session.keyframes.empty()) throw std::invalid_argument("session: no keyframes to continue from");
  if (!(sigma_xy > 0.0) || !(sigma_theta > 0.0))
    throw std::invalid_argument("continueFrom: the start's sigmas must be positive");
  restore(session);
  // The new front end's path goes on past the saved one by a loop's minimum path, so every saved keyframe
  // is a loop candidate of the new ones from the start (paths only grow along the keyframes).
  front_end_.restart(keyframes_.back().path + params_.loop_min_path);
  continuation_ = Continuation{keyframes_.size(), start, sigma_xy, sigma_theta};
}

void LaserSlam::joinSession(const SlamSession& saved, const Pose2& saved_in_map, double sigma_xy,
                            double sigma_theta)
{
  if (saved.keyframes.empty()) throw std::invalid_argument("session: no keyframes to join");
  if (keyframes_.empty()) throw std::invalid_argument("joinSession: this run has no keyframe to tie yet");
  if (!(sigma_xy > 0.0) || !(sigma_theta > 0.0))
    throw std::invalid_argument("joinSession: the tie's sigmas must be positive");
  const std::size_t n = saved.keyframes.size(), m = saved.scans.size();
  if (saved.nodes.size() != n)
    throw std::invalid_argument("session: " + std::to_string(saved.nodes.size()) + " graph nodes for " +
                                std::to_string(n) + " keyframes");
  // The saved graph alone first: an edge or scan naming a keyframe it does not have throws here, before
  // anything of this run changes.
  PoseGraph graph(graphParams(params_));
  for (const auto& node : saved.nodes) graph.addNode(saved_in_map * node);
  for (const auto& e : saved.edges) graph.addEdge(e);
  std::vector<ScanRecord> scans;
  scans.reserve(m + scans_.size());
  for (const auto& s : saved.scans)
  {
    if (s.keyframe != static_cast<std::size_t>(-1) && s.keyframe >= n)
      throw std::invalid_argument("session: a scan on keyframe " + std::to_string(s.keyframe) + " of " +
                                  std::to_string(n));
    // A scan before the saved first keyframe holds its map pose, which moves with the map.
    scans.push_back({s.stamp, s.keyframe, s.keyframe < n ? s.relative : saved_in_map * s.relative});
  }
  // This run after them: indices shifted, paths too (paths only grow along the keyframes, and every saved
  // keyframe is then a loop candidate of this run's).
  const double path_shift = saved.keyframes.back().path + params_.loop_min_path;
  for (std::size_t i = 0; i < keyframes_.size(); ++i) graph.addNode(graph_.node(i));
  for (PoseGraphEdge e : graph_.edges())
  {
    e.from += n;
    e.to += n;
    graph.addEdge(e);
  }
  for (ScanRecord s : scans_)
  {
    if (s.keyframe != static_cast<std::size_t>(-1)) s.keyframe += n;
    scans.push_back(s);
  }
  std::vector<SlamKeyframe> keyframes = saved.keyframes;
  for (SlamKeyframe kf : keyframes_)
  {
    kf.scan += m;
    kf.path += path_shift;
    keyframes.push_back(std::move(kf));
  }
  graph_ = std::move(graph);
  keyframes_ = std::move(keyframes);
  scans_ = std::move(scans);
  front_end_.shiftPath(path_shift);
  // The loop bookkeeping names keyframes by index: it starts afresh, as after restore().
  constraints_ = ConstraintBuilder(params_);
  gate_ = ClosureGate(params_);
  continuation_ = Continuation{n, saved_in_map, sigma_xy, sigma_theta};
  tieToNearestSaved(keyframes_.size() - 1, n, sigma_xy, sigma_theta);
  constraints_.closureAccepted(keyframes_.back().path, graph_);
  graph_optimized_ = true;  // the trajectory gained the saved keyframes
}

}  // namespace line_map_merging

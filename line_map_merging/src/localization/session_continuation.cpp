#include "line_map_merging/localization/session_continuation.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace line_map_merging
{
std::vector<linemap::Segment2> sessionSurfaces(const SlamSession& session)
{
  std::vector<linemap::Segment2> out;
  for (std::size_t k = 0; k < session.keyframes.size() && k < session.nodes.size(); ++k)
    for (const auto& s : session.keyframes[k].joins)
      out.emplace_back(session.nodes[k].apply(s.start), session.nodes[k].apply(s.end));
  return out;
}

std::vector<Sighting> sessionSightings(const SlamSession& session)
{
  std::vector<Sighting> out;
  for (std::size_t k = 0; k < session.keyframes.size() && k < session.nodes.size(); ++k)
    for (const auto& s : session.keyframes[k].joins)
      out.push_back({session.nodes[k].translation(), s.transformed(session.nodes[k])});
  return out;
}

SessionContinuation::SessionContinuation(SlamSession session, const LocalizerParams& localizer,
                                         std::size_t search_scans, const std::optional<linemap::Pose2>& start,
                                         double sigma_xy, double sigma_theta)
    : session_(std::move(session)),
      search_scans_(search_scans),
      given_start_(start),
      sigma_xy_(sigma_xy),
      sigma_theta_(sigma_theta)
{
  if (search_scans_ == 0) throw std::invalid_argument("session continuation: search_scans must be >= 1");
  if (!(sigma_xy_ > 0.0) || !(sigma_theta_ > 0.0))
    throw std::invalid_argument("session continuation: the start's sigmas must be positive");
  if (!given_start_) localizer_ = std::make_unique<LineMapLocalizer>(sessionSurfaces(session_), localizer);
}

SessionContinuation::State SessionContinuation::addScan(const SlamScan& scan, const linemap::Vec2& sensor,
                                                        LaserSlam& slam)
{
  if (state_ != State::kSearching) return state_;
  ++searched_;
  found_ = given_start_;
  if (!found_)
  {
    LocalizerScan in;
    in.stamp = scan.stamp;
    in.points = scan.points;
    in.odom = scan.odom;
    in.sensor = sensor;
    const LocalizerResult result = localizer_->addScan(in);
    // The way in the odometry's frame; without odometry, in the tracked place's, only while it is tracked.
    std::optional<linemap::Pose2> own = scan.odom;
    if (!own)
    {
      if (!result.localized || result.outcome == LocalizerOutcome::kRecovered) way_.clear();
      if (result.localized) own = result.pose;
    }
    if (own) keep(scan, sensor, *own);
    // Judged at the place accepted and at every scan kept on the way while it is tracked: a place the way
    // cannot yet tell from a look-alike one may be told apart a few metres on.
    if (result.outcome == LocalizerOutcome::kRecovered)
    {
      found_ = judged(result.pose, *own);
      if (!found_) localizer_->startGlobalLocalization();
    }
  }
  if (found_)
  {
    // From this scan on: carried back to the held ones by the odometry, the start would take on the
    // odometry's drift over the whole search (metres on a long one), more than the start's sigmas allow.
    held_.clear();
    slam.continueFrom(session_, *found_, sigma_xy_, sigma_theta_);
    state_ = State::kPlaced;
    localizer_.reset();
    judge_.reset();
    session_ = SlamSession();  // the SLAM holds it now
  }
  else if (searched_ >= search_scans_)
  {
    state_ = State::kGaveUp;
    way_.clear();
    rivals_.clear();
    // The search goes on from the SLAM's own poses (the held scans' odometry is a different frame's), its
    // global searches repeated less often: the SLAM maps in the same thread meanwhile.
    LocalizerParams apart = localizer_->params();
    apart.research_every = apart.research_every_apart;
    localizer_ = std::make_unique<LineMapLocalizer>(sessionSurfaces(session_), apart);
  }
  else
    held_.push_back(scan);
  return state_;
}

bool SessionContinuation::giveStart(const linemap::Pose2& start)
{
  if (state_ != State::kSearching) return false;
  given_start_ = start;
  return true;
}

SessionContinuation::State SessionContinuation::afterScan(const SlamScan& scan, const linemap::Vec2& sensor,
                                                          LaserSlam& slam)
{
  if (state_ != State::kGaveUp || slam.keyframes().empty()) return state_;
  ++searched_apart_;
  LocalizerScan in;
  in.stamp = scan.stamp;
  in.points = scan.points;
  in.odom = slam.currentLocal();  // smooth, unlike the map pose, which optimisations move
  in.sensor = sensor;
  const LocalizerResult result = localizer_->addScan(in);
  if (!result.localized)
  {
    confirmation_.reset();
    return state_;
  }
  // The same scan in both maps: the saved frame's pose in the SLAM's.
  const linemap::Pose2 implied = slam.currentPose() * result.pose.inverse();
  switch (confirmation_.add(implied, slam.keyframes().back().path,
                            result.outcome == LocalizerOutcome::kRecovered))
  {
    case PlaceConfirmation::Verdict::kBroken:
      localizer_->startGlobalLocalization();
      return state_;
    case PlaceConfirmation::Verdict::kHolding:
      return state_;
    case PlaceConfirmation::Verdict::kConfirmed:
      break;
  }
  joined_ = judgedJoin(slam, implied, sensor);
  if (!joined_)
  {
    confirmation_.reset();
    localizer_->startGlobalLocalization();
    return state_;
  }
  slam.joinSession(session_, *joined_, sigma_xy_, sigma_theta_);
  state_ = State::kJoined;
  localizer_.reset();
  judge_.reset();
  session_ = SlamSession();  // the SLAM holds it now
  return state_;
}

void SessionContinuation::keep(const SlamScan& scan, const linemap::Vec2& sensor, const linemap::Pose2& own)
{
  const linemap::Pose2 laser = own * linemap::Pose2(sensor.x(), sensor.y(), 0.0);
  if (!way_.move(laser)) return;
  std::vector<linemap::Vec2> returns;
  returns.reserve(scan.points.size());
  // As the localizer takes them: farther returns (and no-return readings at the range limit) are dropped.
  const double max_range = localizer_->params().max_range;
  for (const linemap::Vec2& p : scan.points)
    if ((p - sensor).norm() <= max_range) returns.push_back(p - sensor);
  way_.add(scanSight(laser, returns, point_spacing));
}

std::optional<linemap::Pose2> SessionContinuation::judged(const linemap::Pose2& pose,
                                                          const linemap::Pose2& own)
{
  const auto frame = judgedFrame(way_, pose * own.inverse());
  if (!frame) return std::nullopt;
  return *frame * own;
}

std::optional<linemap::Pose2> SessionContinuation::judgedFrame(const Way& way, const linemap::Pose2& frame)
{
  if (!judge_)
  {
    judge_ = std::make_unique<PlacementJudge>(sessionSurfaces(session_), localizer_->params());
    judge_->setMapFreeSpace(sessionSightings(session_));
  }
  const PlacementJudge::Verdict verdict =
      judge_->judge(way, frame, min_evidence / point_spacing, rival_share, rivals_);
  switch (verdict.outcome)
  {
    case PlacementJudge::Outcome::kAmbiguous:
      ++ambiguous_;
      rivals_ = verdict.rivals;
      rivals_.push_back(verdict.place);
      return std::nullopt;
    case PlacementJudge::Outcome::kSeenThrough:
      // Every place contradicted, the localizer's too: the free-space evidence is not trusted (live on Intel
      // it contradicted every place, offline none; the cause is not found yet), and its place is taken,
      // unless a look-alike place was left open before: then the localizer may well track that one.
      ++seen_through_;
      if (!rivals_.empty()) return std::nullopt;
      return frame;
    case PlacementJudge::Outcome::kPlaced:
      break;
  }
  // The localizer's place of this scan where the judge confirms it: the way, kept along raw odometry (or the
  // SLAM's poses), is bent by its drift, one scan is not.
  const linemap::Pose2 change = frame.inverse() * verdict.place;
  if (std::hypot(change.x, change.y) <= PlaceConfirmation::max_xy &&
      std::fabs(linemap::normalizeAngle(change.theta)) <= PlaceConfirmation::max_theta)
    return frame;
  return verdict.place;
}

std::optional<linemap::Pose2> SessionContinuation::judgedJoin(const LaserSlam& slam,
                                                              const linemap::Pose2& implied,
                                                              const linemap::Vec2& sensor)
{
  // The way: the SLAM's own keyframes at their optimised poses over the last join_window of path, more of the
  // building than the few metres the place was confirmed over, and bent only by what the SLAM's closures
  // left.
  const auto& keyframes = slam.keyframes();
  const double max_range = localizer_->params().max_range, from = keyframes.back().path - join_window;
  Way way(sight_path, sight_turn);
  std::vector<linemap::Vec2> recent;  // the points of the last way_window of path
  for (std::size_t k = 0; k < keyframes.size(); ++k)
  {
    if (keyframes[k].path < from) continue;
    const linemap::Pose2 laser = slam.graph().node(k) * linemap::Pose2(sensor.x(), sensor.y(), 0.0);
    if (!way.move(laser)) continue;
    std::vector<linemap::Vec2> returns;
    returns.reserve(keyframes[k].points.size());
    for (const linemap::Vec2& p : keyframes[k].points)
      if ((p - sensor).norm() <= max_range) returns.push_back(p - sensor);
    Sight sight = scanSight(laser, returns, point_spacing);
    if (keyframes[k].path >= keyframes.back().path - way_window)
      for (const linemap::Vec2& p : sight.points) recent.push_back(laser.apply(p));
    way.add(std::move(sight));
  }
  const linemap::Pose2 tracked = implied.inverse();
  const auto frame = judgedFrame(way, tracked);
  if (!frame) return std::nullopt;
  if (frame->x == tracked.x && frame->y == tracked.y && frame->theta == tracked.theta) return implied;
  // Tracking held a look-alike place and the judge found the robot elsewhere: its place fits the whole way,
  // bent by what drift the SLAM's closures left; the join ties the newest keyframe, so the place is refined
  // on the recent way alone.
  return judge_->refined(recent, *frame).inverse();
}

std::vector<SlamScan> SessionContinuation::takeHeld()
{
  std::vector<SlamScan> out;
  out.swap(held_);
  return out;
}

std::string SessionContinuation::summary() const
{
  std::ostringstream out;
  switch (state_)
  {
    case State::kSearching:
      if (given_start_)
        out << "the next scan is placed at the start given, (" << given_start_->x << ", " << given_start_->y
            << ", " << given_start_->theta << ")";
      else
        out << "looking for the robot in the saved map: scan " << searched_ << " of at most "
            << search_scans_;
      break;
    case State::kPlaced:
      out << "continuing the saved session: found at scan " << searched_ << " at (" << found_->x << ", "
          << found_->y << ", " << found_->theta << ")";
      break;
    case State::kGaveUp:
      out << "the robot was not found in the saved map within " << search_scans_
          << " scans: mapping a new map in its own frame, still looking for it (scan " << searched_apart_
          << " since)";
      break;
    case State::kJoined:
      out << "joined the saved session after " << searched_apart_ << " scans mapped apart: the saved map "
          << "frame lies at (" << joined_->x << ", " << joined_->y << ", " << joined_->theta
          << ") in this map";
      break;
  }
  if (ambiguous_ + seen_through_ > 0)
    out << "; places refused: " << ambiguous_ << " as ambiguous, " << seen_through_
        << " as contradicted by the saved map's free space (taken all the same while no look-alike place was "
           "left open)";
  return out.str();
}

}  // namespace line_map_merging

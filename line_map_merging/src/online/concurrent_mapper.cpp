#include "line_map_merging/online/concurrent_mapper.hpp"

#include <algorithm>
#include <chrono>
#include <sstream>

#include "linemap/atomic_file.hpp"
#include "linemap/small_helpers.hpp"

namespace line_map_merging
{
namespace
{
using Clock = std::chrono::steady_clock;

std::string text(double v)
{
  std::ostringstream out;
  out << v;
  return out.str();
}
}  // namespace

ConcurrentMapper::ConcurrentMapper(std::unique_ptr<OnlineMapper> mapper, bool background)
    : live_(std::move(mapper)), background_(background)
{
  if (!live_) throw std::invalid_argument("ConcurrentMapper: no mapper");
}

std::unique_ptr<ConcurrentMapper> ConcurrentMapper::fromParams(const std::string& method,
                                                               const linemap::ParamSet& params)
{
  return std::make_unique<ConcurrentMapper>(
      std::make_unique<OnlineMapper>(makeMerger(method, params), OnlineMapperParams::fromParams(params)),
      params.getBool("adjust_in_background", true));
}

ConcurrentMapper::~ConcurrentMapper()
{
  if (job_.valid()) job_.wait();
}

void ConcurrentMapper::apply(std::function<void(OnlineMapper&)> call)
{
  call(*live_);
  if (job_.valid()) log_.push_back({std::move(call), {}});
}

ScanOutcome ConcurrentMapper::addScan(const StampedScan& scan)
{
  if (!job_.valid()) return live_->addScan(scan);
  const ScanOutcome outcome = live_->addScan(scan);
  log_.push_back({[scan](OnlineMapper& m) { m.addScan(scan); }, {}});
  return outcome;
}

bool ConcurrentMapper::addTrajectory(const std::vector<StampedPose>& base_poses, std::size_t lane)
{
  if (job_.valid())
  {
    log_.push_back({nullptr, base_poses, lane});
    queued_max_ = std::max(queued_max_, queuedTrajectories());
    return false;
  }
  if (background_ && start(base_poses, lane)) return false;
  return live_->addTrajectory(base_poses, lane);
}

bool ConcurrentMapper::placeLane(std::size_t lane, const linemap::Pose2& lane_in_map)
{
  const bool changed = live_->placeLane(lane, lane_in_map);
  if (job_.valid())
    log_.push_back({[lane, lane_in_map](OnlineMapper& m) { m.placeLane(lane, lane_in_map); }, {}});
  return changed;
}

bool ConcurrentMapper::start(const std::vector<StampedPose>& nodes, std::size_t lane)
{
  const auto t0 = Clock::now();
  std::unique_ptr<OnlineMapper> copy = live_->clone();
  if (!copy) return false;
  last_copy_ms_ = linemap::millisecondsSince(t0);
  job_ = std::async(std::launch::async,
                    [copy = std::move(copy), nodes, lane]() mutable -> Adjusted
                    {
                      const auto w0 = Clock::now();
                      copy->addTrajectory(nodes, lane);
                      return {std::move(copy), linemap::millisecondsSince(w0)};
                    });
  return true;
}

bool ConcurrentMapper::takeResult()
{
  std::unique_ptr<OnlineMapper> adjusted;
  try
  {
    Adjusted result = job_.get();
    adjusted = std::move(result.mapper);
    last_worker_ms_ = result.ms;
  }
  catch (const std::exception&)
  {
    adjusted.reset();
  }
  std::vector<Event> events = std::move(log_);
  log_.clear();
  const auto t0 = Clock::now();
  std::size_t next = 0;
  const bool swapped = adjusted != nullptr;
  if (swapped)
  {
    ++background_adjustments_;
    // The copy was taken when the trajectory came: what the live mapper took since follows it.
    for (; next < events.size() && events[next].apply; ++next) events[next].apply(*adjusted);
    last_replayed_ = next;
    adjusted->adoptAutosave(*live_);
    live_ = std::move(adjusted);
  }
  else
  {
    // A failed copy (out of memory): the live mapper has every call but the trajectory.
    ++background_failures_;
    while (next < events.size() && events[next].apply) ++next;
  }
  // The next queued trajectory starts from the state it came to; the calls after it stay logged for
  // its copy and reach the live mapper now, as they would have.
  if (next < events.size())
  {
    const std::vector<StampedPose> nodes = std::move(events[next].trajectory);
    const std::size_t lane = events[next].lane;
    if (!start(nodes, lane)) live_->addTrajectory(nodes, lane);
    for (++next; next < events.size(); ++next)
    {
      if (events[next].apply && swapped) events[next].apply(*live_);
      if (job_.valid())
        log_.push_back(std::move(events[next]));
      else if (!events[next].apply)
        live_->addTrajectory(events[next].trajectory, events[next].lane);
    }
  }
  last_swap_ms_ = linemap::millisecondsSince(t0);
  return swapped;
}

std::size_t ConcurrentMapper::queuedTrajectories() const
{
  return static_cast<std::size_t>(
      std::count_if(log_.begin(), log_.end(), [](const Event& e) { return !e.apply; }));
}

bool ConcurrentMapper::poll()
{
  if (!job_.valid() || job_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return false;
  return takeResult();
}

bool ConcurrentMapper::finish()
{
  bool changed = false;
  while (job_.valid()) changed = takeResult() || changed;
  return changed;
}

bool ConcurrentMapper::observeTime(double clock, double stamp)
{
  const bool jumped = live_->observeTime(clock, stamp);
  if (job_.valid()) log_.push_back({[clock, stamp](OnlineMapper& m) { m.observeTime(clock, stamp); }, {}});
  return jumped;
}

std::string ConcurrentMapper::admit(double clock, double stamp, bool frame_known, bool& jumped)
{
  jumped = false;
  if (stamp == 0.0)
  {
    countZeroStamp();
    return "stamped zero";
  }
  jumped = observeTime(clock, stamp);
  if (frame_known) return "";
  countDropped();
  return "frame unknown to tf";
}

void ConcurrentMapper::countDropped(std::size_t n)
{
  for (; n > 0; --n) apply([](OnlineMapper& m) { m.countDropped(); });
}

void ConcurrentMapper::countZeroStamp()
{
  apply([](OnlineMapper& m) { m.countZeroStamp(); });
}

void ConcurrentMapper::countIgnoredTrajectory()
{
  apply([](OnlineMapper& m) { m.countIgnoredTrajectory(); });
}

void ConcurrentMapper::countBadPoses(std::size_t n)
{
  apply([n](OnlineMapper& m) { m.countBadPoses(n); });
}

void ConcurrentMapper::reset()
{
  finish();
  live_->reset();
}

void ConcurrentMapper::load(const std::string& path)
{
  finish();
  live_->load(path);
}

namespace
{
/// `action`'s error, if it throws one.
template <class Action>
std::string attemptAll(Action&& action)
{
  try
  {
    action();
    return "";
  }
  catch (const std::exception& e)
  {
    return e.what();
  }
}

MapCommandAnswer answerOf(const std::string& error, const std::string& done)
{
  return {error.empty(), error.empty() ? done : error};
}
}  // namespace

MapCommandAnswer ConcurrentMapper::saveMap(const std::string& path)
{
  finish();
  const std::string error = attemptAll([&] { live_->merger().save(path); });
  return answerOf(error, "saved " + std::to_string(live_->merger().segmentCount()) + " segments to " + path);
}

MapCommandAnswer ConcurrentMapper::loadMap(const std::string& path)
{
  const std::string error = attemptAll([&] { load(path); });
  return answerOf(error, "loaded " + std::to_string(live_->merger().segmentCount()) + " segments, " +
                             std::to_string(live_->merger().keyframeCount()) + " keyframes from " + path);
}

MapCommandAnswer ConcurrentMapper::appendMap(const std::string& path, const linemap::Pose2& placed)
{
  std::size_t added = 0;
  const std::string error = attemptAll(
      [&]
      {
        finish();
        added = live_->appendText(linemap::readWholeFile(path, "map file"), path, placed);
      });
  return answerOf(error, "merged " + std::to_string(added) + " keyframes of " + path + " into the map");
}

std::string ConcurrentMapper::autosave(const std::string& path, double now, bool wait)
{
  if (wait) finish();  // the last save: the newest map
  return live_->autosave(path, now, wait);
}

std::vector<std::pair<std::string, std::string>> ConcurrentMapper::diagnostics() const
{
  auto out = live_->diagnostics();
  auto n = [](std::size_t v) { return std::to_string(v); };
  out.insert(out.end(), {{"adjusting in the background", job_.valid() ? "yes" : "no"},
                         {"trajectories queued", n(queuedTrajectories())},
                         {"most trajectories queued", n(queued_max_)},
                         {"background adjustments", n(background_adjustments_)},
                         {"failed background adjustments", n(background_failures_)},
                         {"last copy for adjustment [ms]", text(last_copy_ms_)},
                         {"last background adjustment [ms]", text(last_worker_ms_)},
                         {"last swap [ms]", text(last_swap_ms_)},
                         {"calls replayed at the last swap", n(last_replayed_)}});
  return out;
}

}  // namespace line_map_merging

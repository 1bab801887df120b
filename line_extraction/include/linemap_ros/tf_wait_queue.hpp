// ROS side (not part of the ROS-free core): holds stamped messages until tf can place them.
#pragma once

#include <ros/callback_queue_interface.h>
#include <ros/message_event.h>
#include <ros/node_handle.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>

#include <algorithm>
#include <atomic>
#include <boost/make_shared.hpp>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "linemap_ros/param_loader.hpp"
#include "linemap_ros/transport.hpp"

namespace linemap_ros
{
/// Whether a tf2 canTransform/lookup error says the stamp lies before the data of its chain (tf2's
/// "extrapolation into the past"): tf data comes in time order, so such a stamp is never placed
/// however long one waits (after a time jump, say, or older than the buffer keeps).
inline bool extrapolatesIntoThePast(const std::string& tf_error)
{
  return tf_error.find("into the past") != std::string::npos;
}

/// In place of tf2_ros::MessageFilter, whose bookkeeping loses messages: it registers a message's
/// transformable request with the buffer before it puts the message in its list, so a transform
/// arriving in between answers a request no listed message owns, and the message then waits for
/// ever (seen under load in the parity rostests; later transforms did not release it).
/// Here every change of the buffer schedules a pass over the held messages on the node handle's
/// callback queue, which also runs the subscription that adds them: one thread, arrival order.
template <class M>
class TfWaitQueue
{
 public:
  using Event = ros::MessageEvent<const M>;
  using Ready = std::function<void(const Event&)>;
  using Failed = std::function<void(const Event&, const std::string& why)>;
  /// ROS time and wall time now.
  using Clock = std::function<std::pair<ros::Time, ros::WallTime>()>;

  /// `capacity`: the oldest held message is dropped beyond it. `max_wait`: a message is dropped when,
  /// for longer than this on both clocks, it has waited (ROS time since its receipt, wall time since it
  /// was added) and its chain of transforms has not moved on (the latest time tf can place its frame at);
  /// zero waits without a limit. ROS time alone would give a tf publisher (a SLAM optimising) only a few
  /// milliseconds of wall time when a bag plays fast, and scans were dropped so; wall time alone would
  /// drop what waits while the bag is paused. A chain that moves on is a publisher catching up (a SLAM
  /// behind its scans after a search): its messages wait for it, however far behind it is. A message
  /// stamped before the buffer's data for its chain is dropped too: it never fits
  /// (extrapolatesIntoThePast).
  TfWaitQueue(tf2::BufferCore& tf, std::string target_frame, std::size_t capacity, ros::Duration max_wait,
              ros::NodeHandle& nh, Ready ready, Failed failed)
      : tf_(tf),
        target_(std::move(target_frame)),
        capacity_(std::max<std::size_t>(1, capacity)),
        max_wait_(max_wait),
        queue_(nh.getCallbackQueue()),
        ready_(std::move(ready)),
        failed_(std::move(failed))
  {
    changed_ = tf_._addTransformsChangedListener([this] { schedule(); });
  }

  ~TfWaitQueue()
  {
    subscriber_.shutdown();
    tf_._removeTransformsChangedListener(changed_);
    queue_->removeByID(owner());
  }

  TfWaitQueue(const TfWaitQueue&) = delete;  // the buffer and the callback queue call back into it
  TfWaitQueue& operator=(const TfWaitQueue&) = delete;

  /// Subscribes `topic` on the node handle given at construction (TCP_NODELAY) and holds what arrives;
  /// `arrival` runs first, in arrival order, and may turn a message away (false).
  void subscribe(ros::NodeHandle& nh, const std::string& topic, std::uint32_t queue_size,
                 std::function<bool(const Event&)> arrival = {})
  {
    subscriber_ = nh.subscribe<M>(topic, queue_size,
                                  boost::function<void(const Event&)>(
                                      [this, arrival](const Event& e)
                                      {
                                        if (!arrival || arrival(e)) add(e);
                                      }),
                                  {}, noDelay());
  }

  /// The clocks waits are measured on (a test's own; by default ROS time and wall time).
  void useClock(Clock clock) { clock_ = std::move(clock); }

  /// On the callback queue given at construction (a subscription callback of the same node handle).
  void add(const Event& event) { add(event, clock_().second); }

  /// The same with `added`, the wall time the wait starts from (a test may date it back).
  void add(const Event& event, const ros::WallTime& added)
  {
    held_.push_back({event, added});
    if (held_.size() > capacity_)
    {
      const Event oldest = held_.front().event;
      held_.pop_front();
      failed_(oldest, "more than " + std::to_string(capacity_) + " messages waiting for tf");
    }
    release();
  }

  /// Drops every held message (a time jump: their stamps belong to the old time line); how many.
  std::size_t clear()
  {
    const std::size_t n = held_.size();
    held_.clear();
    progress_.clear();
    return n;
  }

  std::size_t held() const { return held_.size(); }

 private:
  /// Hands on, in arrival order, every held message tf can now place; drops those that waited too
  /// long or that tf can never place. A frame's messages keep their order: behind one that must
  /// still wait, the later ones of its frame wait too. (tf keeps arriving on the listener's thread
  /// during a pass, so a later message may become placeable after an earlier one was found not to
  /// be: passing it would reorder a sensor's stream, which under load reordered scans by more than
  /// a second across the log's gaps and looked like time jumping back.)
  void release()
  {
    const auto [now, wall_now] = clock_();
    std::vector<std::string> waiting_frames, followed_frames;
    for (auto it = held_.begin(); it != held_.end();)
    {
      const M& msg = *it->event.getConstMessage();
      const std::string frame = stripLeadingSlash(msg.header.frame_id);
      const bool behind =
          std::find(waiting_frames.begin(), waiting_frames.end(), frame) != waiting_frames.end();
      std::string why;
      if (!behind && (frame == target_ || tf_.canTransform(target_, frame, msg.header.stamp)))
        why.clear();
      else if (neverPlaceable(frame, msg.header.stamp))
        why = "stamped before the tf buffer's data";
      else if (waitedTooLong(*it, frame, now, wall_now, followed_frames))
        why = "waited longer than " + std::to_string(max_wait_.toSec()) + " s for tf to move on";
      else
      {
        if (!behind) waiting_frames.push_back(frame);
        ++it;
        continue;
      }
      const Event event = it->event;
      it = held_.erase(it);
      why.empty() ? ready_(event) : failed_(event, why + " (" + target_ + " -> " + frame + ")");
    }
  }

  struct Held
  {
    Event event;
    ros::WallTime added;
  };

  /// Whether `held` waited longer than the limit, on both clocks, since it came and since its frame's
  /// chain last moved on. The chain is looked at once per pass (`followed_frames`).
  bool waitedTooLong(const Held& held, const std::string& frame, const ros::Time& now,
                     const ros::WallTime& wall_now, std::vector<std::string>& followed_frames)
  {
    if (max_wait_.isZero()) return false;
    if (std::find(followed_frames.begin(), followed_frames.end(), frame) == followed_frames.end())
    {
      followed_frames.push_back(frame);
      follow(frame, now, wall_now);
    }
    ros::Time since = held.event.getReceiptTime();
    ros::WallTime wall_since = held.added;
    if (const auto p = progress_.find(frame); p != progress_.end())
    {
      since = std::max(since, p->second.moved);
      wall_since = std::max(wall_since, p->second.wall_moved);
    }
    return now - since > max_wait_ && (wall_now - wall_since).toSec() > max_wait_.toSec();
  }

  /// Notes when the latest time tf can place `frame` at changes (data newer, or older after a jump).
  void follow(const std::string& frame, const ros::Time& now, const ros::WallTime& wall_now)
  {
    ros::Time latest;
    try
    {
      latest = tf_.lookupTransform(target_, frame, ros::Time(0)).header.stamp;
    }
    catch (const tf2::TransformException&)
    {
      return;  // no chain yet: nothing moves
    }
    auto [p, added] = progress_.try_emplace(frame, Progress{latest, now, wall_now});
    if (!added && p->second.latest != latest) p->second = {latest, now, wall_now};
  }

  bool neverPlaceable(const std::string& frame, const ros::Time& stamp) const
  {
    std::string error;
    return !tf_.canTransform(target_, frame, stamp, &error) && extrapolatesIntoThePast(error);
  }

  /// From tf's listener thread: one pass at a time is queued, whatever the number of transforms.
  void schedule()
  {
    if (scheduled_.exchange(true)) return;
    queue_->addCallback(boost::make_shared<Pass>(this), owner());
  }

  struct Pass : ros::CallbackInterface
  {
    explicit Pass(TfWaitQueue* q) : queue(q) {}
    CallResult call() override
    {
      queue->scheduled_ = false;  // before the pass: a change during it schedules another
      queue->release();
      return Success;
    }
    TfWaitQueue* queue;
  };

  std::uint64_t owner() const { return reinterpret_cast<std::uint64_t>(this); }

  tf2::BufferCore& tf_;
  const std::string target_;
  const std::size_t capacity_;
  const ros::Duration max_wait_;
  ros::CallbackQueueInterface* queue_;
  Ready ready_;
  Failed failed_;
  Clock clock_ = [] { return std::make_pair(ros::Time::now(), ros::WallTime::now()); };
  /// Per frame: the latest time tf can place it at, and when that last changed on both clocks.
  struct Progress
  {
    ros::Time latest, moved;
    ros::WallTime wall_moved;
  };
  std::map<std::string, Progress> progress_;
  std::deque<Held> held_;
  std::atomic<bool> scheduled_{false};
  boost::signals2::connection changed_;
  ros::Subscriber subscriber_;  // last: unsubscribed first
};
}  // namespace linemap_ros

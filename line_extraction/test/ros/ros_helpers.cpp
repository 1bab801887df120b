// gtests of the ROS-side helpers, run by rostest (test/ros/ros_helpers.test): TfWaitQueue, and the
// parameters every nodelet reads alike (param_loader.hpp).
// The transforms go straight into a tf2::BufferCore and the queue's passes run on a callback queue
// of the test's own, spun by hand, so every step is an event the test causes.
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2/buffer_core.h>

#include <functional>
#include <string>
#include <vector>

#include "linemap_ros/param_loader.hpp"
#include "linemap_ros/tf_wait_queue.hpp"

namespace
{
using Scan = sensor_msgs::LaserScan;
using Event = ros::MessageEvent<const Scan>;
using Queue = linemap_ros::TfWaitQueue<Scan>;

struct TfWaitQueueTest : ::testing::Test
{
  TfWaitQueueTest() : buffer(ros::Duration(10.0)) { nh.setCallbackQueue(&callbacks); }

  void setTf(double stamp, const std::string& child = "laser")
  {
    geometry_msgs::TransformStamped t;
    t.header.frame_id = "map";
    t.header.stamp = ros::Time(stamp);
    t.child_frame_id = child;
    t.transform.rotation.w = 1.0;
    buffer.setTransform(t, "test");
  }

  Event scan(double stamp, const std::string& frame = "laser", ros::Time receipt = ros::Time::now())
  {
    auto msg = boost::make_shared<Scan>();
    msg->header.frame_id = frame;
    msg->header.stamp = ros::Time(stamp);
    return Event(msg, receipt);
  }

  std::unique_ptr<Queue> make(std::size_t capacity = 100, double max_wait = 0.0)
  {
    return std::make_unique<Queue>(
        buffer, "map", capacity, ros::Duration(max_wait), nh,
        [this](const Event& e)
        {
          delivered.push_back(e.getConstMessage()->header.stamp.toSec());
          if (on_delivery) on_delivery();
        },
        [this](const Event& e, const std::string& why)
        {
          dropped.push_back(e.getConstMessage()->header.stamp.toSec());
          reasons.push_back(why);
        });
  }

  ros::NodeHandle nh;
  ros::CallbackQueue callbacks;
  tf2::BufferCore buffer;
  std::vector<double> delivered, dropped;
  std::vector<std::string> reasons;
  std::function<void()> on_delivery;  // runs after each delivery
};

TEST_F(TfWaitQueueTest, HoldsUntilTfReachesTheStampThenDeliversInArrivalOrder)
{
  auto queue = make();
  for (double t : {1.0, 2.0, 3.0}) queue->add(scan(t));
  EXPECT_TRUE(delivered.empty());
  EXPECT_EQ(queue->held(), 3u);
  setTf(0.0);
  setTf(2.5);  // interpolation reaches 1 and 2, not 3
  callbacks.callAvailable();
  EXPECT_EQ(delivered, (std::vector<double>{1.0, 2.0}));
  EXPECT_EQ(queue->held(), 1u);
  setTf(4.0);
  callbacks.callAvailable();
  EXPECT_EQ(delivered, (std::vector<double>{1.0, 2.0, 3.0}));
  EXPECT_EQ(queue->held(), 0u);
  EXPECT_TRUE(dropped.empty());
}

TEST_F(TfWaitQueueTest, LaterMessageOfAFrameWaitsBehindAnEarlierOneThatWaits)
{
  // tf arrives on the listener's thread during a pass: here the delivery of another frame's message
  // inserts it, after laser 5.0 was found waiting and before laser 6.0 is looked at.
  auto queue = make();
  for (double t : {0.0, 4.0}) setTf(t);
  for (double t : {0.0, 10.0}) setTf(t, "laser2");
  callbacks.callAvailable();
  queue->add(scan(5.0));
  queue->add(scan(12.0, "laser2"));
  queue->add(scan(6.0));
  EXPECT_TRUE(delivered.empty());
  on_delivery = [this]
  {
    on_delivery = nullptr;
    setTf(7.0);
  };
  setTf(13.0, "laser2");
  callbacks.callAvailable();  // 12.0 passes, and laser's transform up to 7 arrives meanwhile
  callbacks.callAvailable();
  EXPECT_EQ(delivered, (std::vector<double>{12.0, 5.0, 6.0}));  // laser's order kept
}

TEST_F(TfWaitQueueTest, PlaceableMessagePassesAtOnceAndTheMapFrameNeedsNoTf)
{
  auto queue = make();
  queue->add(scan(5.0, "map"));  // an empty buffer: the target frame itself
  EXPECT_EQ(delivered, (std::vector<double>{5.0}));
  setTf(0.0);
  setTf(10.0);
  queue->add(scan(7.0, "/laser"));  // a leading slash (ROS 1 tf) is tolerated
  EXPECT_EQ(delivered, (std::vector<double>{5.0, 7.0}));
  EXPECT_EQ(queue->held(), 0u);
}

TEST_F(TfWaitQueueTest, MessageHeldLongerThanTheLimitIsDroppedEvenWhenTfComes)
{
  auto queue = make(100, 0.5);
  queue->add(scan(1.0, "laser", ros::Time::now() - ros::Duration(2.0)),
             ros::WallTime::now() - ros::WallDuration(2.0));
  ASSERT_EQ(dropped, (std::vector<double>{1.0}));
  EXPECT_NE(reasons[0].find("waited longer"), std::string::npos) << reasons[0];
  queue->add(scan(2.0));  // just received: waits
  setTf(0.0);
  setTf(3.0);
  callbacks.callAvailable();
  EXPECT_EQ(delivered, (std::vector<double>{2.0}));
}

TEST_F(TfWaitQueueTest, LimitMustPassOnBothClocks)
{
  // A bag played at rate 20: 2 s of ROS time went by in 0.1 s of wall time, and a SLAM publishing
  // map -> odom after its optimisation is not late yet. A paused bag: wall time went by, ROS time
  // did not. Either message still waits, and is delivered when tf comes.
  auto queue = make(100, 0.5);
  queue->add(scan(1.0, "laser", ros::Time::now() - ros::Duration(2.0)),
             ros::WallTime::now() - ros::WallDuration(0.1));
  queue->add(scan(2.0, "laser", ros::Time::now()), ros::WallTime::now() - ros::WallDuration(2.0));
  setTf(0.0);  // a pass; neither is placeable yet
  callbacks.callAvailable();
  EXPECT_TRUE(dropped.empty());
  setTf(3.0);
  callbacks.callAvailable();
  EXPECT_EQ(delivered, (std::vector<double>{1.0, 2.0}));
}

TEST_F(TfWaitQueueTest, MessageWaitsWhileItsChainMovesOnAndIsDroppedWhenItStops)
{
  // A SLAM catching up after a search: its map -> laser comes later than the limit after each scan, but
  // keeps moving on. The clocks are the test's own: both advance together here.
  auto queue = make(100, 0.5);
  ros::Time now(100.0);
  ros::WallTime wall_now(1000.0);
  queue->useClock([&] { return std::make_pair(now, wall_now); });
  const auto wait = [&](double seconds)
  {
    now += ros::Duration(seconds);
    wall_now += ros::WallDuration(seconds);
  };
  setTf(0.0);
  setTf(1.0);
  callbacks.callAvailable();
  queue->add(scan(5.0, "laser", now));
  for (double t : {2.0, 3.0, 4.0})
  {
    wait(0.4);  // 1.2 s since receipt in all, never 0.5 s without tf moving on
    setTf(t);
    callbacks.callAvailable();
  }
  EXPECT_TRUE(dropped.empty());
  wait(0.4);
  setTf(6.0);
  callbacks.callAvailable();
  EXPECT_EQ(delivered, (std::vector<double>{5.0}));

  // The publisher stops: another frame's tf comes, this chain's does not move on.
  queue->add(scan(8.0, "laser", now));
  wait(0.3);
  setTf(1.0, "laser2");
  callbacks.callAvailable();
  EXPECT_TRUE(dropped.empty());  // 0.3 s: still within the limit
  wait(0.3);
  setTf(2.0, "laser2");
  callbacks.callAvailable();
  ASSERT_EQ(dropped, (std::vector<double>{8.0}));
  EXPECT_NE(reasons[0].find("waited longer"), std::string::npos) << reasons[0];
}

TEST_F(TfWaitQueueTest, BeyondCapacityTheOldestIsDropped)
{
  auto queue = make(2);
  for (double t : {1.0, 2.0, 3.0}) queue->add(scan(t));
  EXPECT_EQ(dropped, (std::vector<double>{1.0}));
  EXPECT_EQ(queue->held(), 2u);
  EXPECT_EQ(queue->clear(), 2u);
  EXPECT_EQ(queue->held(), 0u);
}

TEST_F(TfWaitQueueTest, StampBeforeTheBuffersDataIsDropped)
{
  auto queue = make();
  setTf(100.0);
  setTf(101.0);
  queue->add(scan(50.0));  // before the buffer's data (which comes in time order): never placed
  EXPECT_EQ(dropped, (std::vector<double>{50.0}));
  EXPECT_NE(reasons[0].find("before the tf buffer's data"), std::string::npos) << reasons[0];
  queue->add(scan(102.0));  // ahead of tf: waits
  EXPECT_EQ(queue->held(), 1u);
}

TEST_F(TfWaitQueueTest, ManyTransformsScheduleOnePass)
{
  auto queue = make();
  queue->add(scan(1.0));
  for (int i = 0; i <= 100; ++i) setTf(0.05 * i);
  EXPECT_EQ(callbacks.callOne(), ros::CallbackQueue::Called);
  EXPECT_EQ(callbacks.callOne(), ros::CallbackQueue::Empty);
  EXPECT_EQ(delivered, (std::vector<double>{1.0}));
}

TEST_F(TfWaitQueueTest, DestroyedQueueLeavesNoPassBehind)
{
  {
    auto queue = make();
    queue->add(scan(1.0));
    setTf(0.0);  // schedules a pass
  }
  setTf(2.0);  // the listener is gone too
  EXPECT_EQ(callbacks.callOne(), ros::CallbackQueue::Empty);
  EXPECT_TRUE(delivered.empty());
}
// Each test its own private namespace on the master: no test sees another's parameters.
TEST(SharedParams, QueueSizeAndTfCacheDefaultWhenUnset)
{
  const ros::NodeHandle pnh("~unset");
  EXPECT_EQ(linemap_ros::queueSizeParam(pnh), 1000u);
  EXPECT_EQ(linemap_ros::queueSizeParam(pnh, 7), 7u);
  EXPECT_DOUBLE_EQ(linemap_ros::tfCacheParam(pnh).toSec(), 600.0);
}

TEST(SharedParams, QueueSizeAndTfCacheAsSet)
{
  ros::NodeHandle pnh("~set");
  pnh.setParam("queue_size", 25);
  pnh.setParam("tf_cache", 42.5);
  EXPECT_EQ(linemap_ros::queueSizeParam(pnh), 25u);
  EXPECT_DOUBLE_EQ(linemap_ros::tfCacheParam(pnh).toSec(), 42.5);
}

TEST(SharedParams, OutOfRangeValuesAreRaisedToTheSmallestThatWorks)
{
  ros::NodeHandle pnh("~bad");
  pnh.setParam("queue_size", -3);
  pnh.setParam("tf_cache", 2.0);
  EXPECT_EQ(linemap_ros::queueSizeParam(pnh), 1u);
  EXPECT_DOUBLE_EQ(linemap_ros::tfCacheParam(pnh).toSec(), 10.0);
  pnh.setParam("queue_size", 0);
  pnh.setParam("tf_cache", -1.0);
  EXPECT_EQ(linemap_ros::queueSizeParam(pnh), 1u);
  EXPECT_DOUBLE_EQ(linemap_ros::tfCacheParam(pnh).toSec(), 10.0);
}
}  // namespace

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_ros_helpers");
  ros::NodeHandle nh;  // starts the node (ros::Time::now() is wall time: no use_sim_time)
  return RUN_ALL_TESTS();
}

#include "line_map_eval/datasets/bag_writer.hpp"

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Path.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "line_map_eval/batch/progress.hpp"
#include "linemap_ros/message_conversions.hpp"

namespace line_map_eval
{
namespace
{
rosbag::CompressionType compressionFromName(const std::string& name)
{
  if (name == "none") return rosbag::compression::Uncompressed;
  if (name == "lz4") return rosbag::compression::LZ4;
  if (name == "bz2") return rosbag::compression::BZ2;
  throw std::invalid_argument("bag compression must be none, lz4 or bz2, not '" + name + "'");
}

void validate(const Recording& rec, const std::string& path, const BagWriterOptions& options)
{
  const auto fail = [&](const std::string& what)
  { throw std::runtime_error(path + ": cannot write: " + what); };
  if (rec.scans.empty()) fail("the recording has no scans");
  if (options.trajectory_every == 0) fail("trajectory_every must be at least 1");
  if (rec.geometry.beam_count == 0) fail("the recording's beam_count is 0");
  for (std::size_t i = 0; i < rec.scans.size(); ++i)
  {
    const RecordedScan& s = rec.scans[i];
    if (!(s.stamp > 0.0) || !std::isfinite(s.stamp))
      fail("scan " + std::to_string(i) + " has stamp " + std::to_string(s.stamp) + " (must be positive)");
    if (i > 0 && !(s.stamp > rec.scans[i - 1].stamp))
      fail("scan " + std::to_string(i) + " stamp does not increase");
    if (s.ranges.size() != rec.geometryOf(s).beam_count)
      fail("scan " + std::to_string(i) + " has " + std::to_string(s.ranges.size()) +
           " ranges, geometry says " + std::to_string(rec.geometryOf(s).beam_count));
  }
  for (std::size_t k = 0; k < rec.keyframes.size(); ++k)
  {
    const std::size_t i = rec.keyframes[k].scan_index;
    if (i >= rec.scans.size())
      fail("keyframe " + std::to_string(k) + " refers to missing scan " + std::to_string(i));
    if (k > 0 && i <= rec.keyframes[k - 1].scan_index)
      fail("keyframe " + std::to_string(k) + " is not after the previous keyframe");
  }
}
}  // namespace

void writeBag(const Recording& rec, const std::string& path, const BagWriterOptions& options,
              BagWriteSummary* summary)
{
  validate(rec, path, options);
  const rosbag::CompressionType compression = compressionFromName(options.compression);
  if (!ros::Time::isValid()) ros::Time::init();

  BagWriteSummary info;
  info.scans = rec.scans.size();
  info.keyframes = rec.keyframes.size();
  info.duration = rec.scans.back().stamp - rec.scans.front().stamp;
  std::vector<double> periods;
  for (std::size_t i = 1; i < rec.scans.size(); ++i)
    periods.push_back(rec.scans[i].stamp - rec.scans[i - 1].stamp);
  if (!periods.empty())
  {
    std::nth_element(periods.begin(), periods.begin() + periods.size() / 2, periods.end());
    info.scan_time = periods[periods.size() / 2];
  }

  try
  {
    rosbag::Bag bag;
    bag.open(path, rosbag::bagmode::Write);
    bag.setCompression(compression);

    const ros::Time t0(rec.scans.front().stamp);
    tf2_msgs::TFMessage static_tf;
    static_tf.transforms.push_back(
        linemap_ros::toTransform(rec.base_to_laser, options.base_frame, options.laser_frame, t0));
    // Marked latched like tf2_ros::StaticTransformBroadcaster, so `rosbag play` re-latches it.
    auto header = boost::make_shared<ros::M_string>();
    (*header)["callerid"] = "/carmen_to_bag";
    (*header)["latching"] = "1";
    (*header)["type"] = ros::message_traits::datatype<tf2_msgs::TFMessage>();
    (*header)["md5sum"] = ros::message_traits::md5sum<tf2_msgs::TFMessage>();
    (*header)["message_definition"] = ros::message_traits::definition<tf2_msgs::TFMessage>();
    bag.write("/tf_static", t0, static_tf, header);

    sensor_msgs::LaserScan scan;
    scan.header.frame_id = options.laser_frame;
    scan.time_increment = 0.0f;
    scan.scan_time = static_cast<float>(info.scan_time);

    nav_msgs::Path path_msg;
    path_msg.header.frame_id = options.map_frame;
    Pose2 map_to_odom;  // identity until the first emission
    std::size_t next_keyframe = 0;
    const bool with_trajectory = !rec.keyframes.empty();

    ProgressBar bar("writing " + path, rec.scans.size(), options.progress);
    for (std::size_t i = 0; i < rec.scans.size(); ++i)
    {
      const RecordedScan& s = rec.scans[i];
      const ros::Time stamp(s.stamp);
      bool emit = false;
      if (next_keyframe < rec.keyframes.size() && rec.keyframes[next_keyframe].scan_index == i)
      {
        const CorrectedKeyframe& kf = rec.keyframes[next_keyframe];
        geometry_msgs::PoseStamped pose;
        pose.header.frame_id = options.map_frame;
        pose.header.stamp = stamp;
        pose.pose = linemap_ros::toPoseMsg(kf.pose);
        path_msg.poses.push_back(pose);
        ++next_keyframe;
        emit = next_keyframe % options.trajectory_every == 0 || next_keyframe == rec.keyframes.size();
        // The stand-in for a back end's loop closure: after an emission, map->base_link at
        // this keyframe equals its corrected pose.
        if (emit) map_to_odom = kf.pose * s.odom.inverse();
      }

      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(
          linemap_ros::toTransform(s.odom, options.odom_frame, options.base_frame, stamp));
      if (with_trajectory)
        tf.transforms.push_back(
            linemap_ros::toTransform(map_to_odom, options.map_frame, options.odom_frame, stamp));
      bag.write("/tf", stamp, tf);

      // Each scan's own geometry: some sensors change start angle and beam count between scans.
      const ScanGeometry& g = rec.geometryOf(s);
      scan.header.stamp = stamp;
      scan.angle_min = static_cast<float>(g.angle_min);
      scan.angle_increment = static_cast<float>(g.angle_increment);
      scan.angle_max =
          static_cast<float>(g.angle_min + g.angle_increment * static_cast<double>(g.beam_count - 1));
      scan.range_min = static_cast<float>(g.range_min);
      scan.range_max = static_cast<float>(g.range_max);
      scan.ranges = s.ranges;
      bag.write(options.scan_topic, stamp, scan);

      if (emit)
      {
        path_msg.header.stamp = stamp;
        bag.write(options.trajectory_topic, stamp, path_msg);
        ++info.trajectory_emissions;
      }
      bar.update(i + 1);
    }
    bar.finish();
    bag.close();
  }
  catch (const rosbag::BagException& e)
  {
    throw std::runtime_error(path + ": " + e.what());
  }
  if (summary) *summary = info;
}

}  // namespace line_map_eval

// ROS side (not part of the ROS-free core): the transport every linemap subscription asks for.
#pragma once

#include <ros/transport_hints.h>

namespace linemap_ros
{
/// TCP_NODELAY on the publisher's socket. With roscpp's default, Nagle's algorithm holds a small
/// message until the previous one is acknowledged, and the receiver delays its acknowledgement by
/// up to 40 ms, which became most of the pipeline's latency (rosbag play -> extractor, rosbag play ->
/// tf listener). Messages are sent as they come.
inline ros::TransportHints noDelay()
{
  return ros::TransportHints().tcpNoDelay();
}
}  // namespace linemap_ros

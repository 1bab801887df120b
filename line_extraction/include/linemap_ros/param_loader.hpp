// ROS side (not part of the ROS-free core): reads every parameter under a node handle's
// namespace into a linemap::ParamSet, nested maps flattened to "block/name" keys, so the
// nodelets hand the core exactly what config/*.yaml and `linemap_batch --param` use.
#pragma once

#include <ros/console.h>
#include <ros/duration.h>
#include <ros/node_handle.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <cstdint>
#include <sstream>
#include <string>
#include <tuple>

#include "linemap/params.hpp"

namespace linemap_ros
{
inline void flattenParam(const std::string& key, XmlRpc::XmlRpcValue& value, linemap::ParamSet& out)
{
  switch (value.getType())
  {
    case XmlRpc::XmlRpcValue::TypeStruct:
      for (auto& entry : value)
        flattenParam(key.empty() ? entry.first : key + "/" + entry.first, entry.second, out);
      break;
    case XmlRpc::XmlRpcValue::TypeBoolean:
      out.set(key, static_cast<bool>(value) ? "true" : "false");
      break;
    case XmlRpc::XmlRpcValue::TypeInt:
      out.set(key, std::to_string(static_cast<int>(value)));
      break;
    case XmlRpc::XmlRpcValue::TypeDouble:
    {
      std::ostringstream s;
      s.precision(17);
      s << static_cast<double>(value);
      out.set(key, s.str());
      break;
    }
    case XmlRpc::XmlRpcValue::TypeString:
      out.set(key, static_cast<std::string>(value));
      break;
    default:
      break;  // arrays, dates and binary blobs are no parameters of ours
  }
}

/// All parameters below `nh`'s namespace (typically the private node handle).
inline linemap::ParamSet loadParamSet(const ros::NodeHandle& nh)
{
  linemap::ParamSet params;
  XmlRpc::XmlRpcValue tree;
  if (nh.getParam(nh.getNamespace(), tree)) flattenParam("", tree, params);
  return params;
}

/// tf2 rejects frame ids with a leading slash (ROS 1 tf accepted them): strip it.
inline std::string stripLeadingSlash(const std::string& frame)
{
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

/// The REP-105 frames every linemap nodelet reads: ~map_frame, ~base_frame, ~odom_frame.
inline std::tuple<std::string, std::string, std::string> frameParams(const ros::NodeHandle& pnh)
{
  const auto frame = [&](const char* name, const char* fallback)
  { return stripLeadingSlash(pnh.param<std::string>(name, fallback)); };
  return {frame("map_frame", "map"), frame("base_frame", "base_link"), frame("odom_frame", "odom")};
}

/// ~queue_size: the messages a subscription (or a publisher) holds; a full queue drops its oldest without a
/// trace. Below 1, a warning naming the parameter, and 1.
inline std::uint32_t queueSizeParam(const ros::NodeHandle& pnh, int fallback = 1000)
{
  const int value = pnh.param("queue_size", fallback);
  if (value >= 1) return static_cast<std::uint32_t>(value);
  ROS_WARN_STREAM("parameter " << pnh.resolveName("queue_size") << " must be at least 1, got " << value
                               << ": using 1");
  return 1;
}

/// ~tf_cache [s]: how far back the tf buffer holds transforms. A node that lags the bag (the SLAM searching a
/// saved session) needs transforms that far back. Below 10 s, or not a number, a warning naming the
/// parameter, and 10 s.
inline ros::Duration tfCacheParam(const ros::NodeHandle& pnh, double fallback = 600.0)
{
  constexpr double kShortest = 10.0;
  const double value = pnh.param("tf_cache", fallback);
  if (value >= kShortest) return ros::Duration(value);
  ROS_WARN_STREAM("parameter " << pnh.resolveName("tf_cache") << " must be at least " << kShortest
                               << " s, got " << value << ": using " << kShortest << " s");
  return ros::Duration(kShortest);
}

}  // namespace linemap_ros

// Stand-alone executable: loads the merging nodelet into its own process.
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv)
{
  ros::init(argc, argv, "line_map_merging");
  nodelet::Loader loader;
  const nodelet::M_string remappings(ros::names::getRemappings());
  const nodelet::V_string args;
  if (!loader.load(ros::this_node::getName(), "line_map_merging/LineMapMergingNodelet", remappings, args))
  {
    ROS_FATAL("line_map_merging: cannot load line_map_merging/LineMapMergingNodelet");
    return 1;
  }
  ros::spin();
  return 0;
}

// line_extraction_node: the LineExtractionNodelet loaded in-process, for use
// without a nodelet manager (rosrun line_extraction line_extraction_node).
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv)
{
  ros::init(argc, argv, "line_extraction");
  nodelet::Loader loader;
  const nodelet::M_string remappings(ros::names::getRemappings());
  const nodelet::V_string my_argv(argv + 1, argv + argc);
  if (!loader.load(ros::this_node::getName(), "line_extraction/LineExtractionNodelet", remappings, my_argv))
  {
    ROS_FATAL("line_extraction_node: could not load line_extraction/LineExtractionNodelet");
    return 1;
  }
  ros::spin();
  return 0;
}

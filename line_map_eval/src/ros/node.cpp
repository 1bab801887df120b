// Runs the evaluator nodelet as a stand-alone node.
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv)
{
  ros::init(argc, argv, "line_map_eval");
  nodelet::Loader loader;
  nodelet::M_string remappings(ros::names::getRemappings());
  nodelet::V_string my_argv(argv + 1, argv + argc);
  if (!loader.load(ros::this_node::getName(), "line_map_eval/LineMapEvalNodelet", remappings, my_argv))
  {
    ROS_FATAL("line_map_eval: could not load line_map_eval/LineMapEvalNodelet");
    return 1;
  }
  ros::spin();
  return 0;
}

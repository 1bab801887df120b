#!/usr/bin/python3
"""Rostest checker (test/node_variants.test): the three stand-alone nodes run the pipeline on a
short simulated square room: line_segments, line_map and map_quality appear, and the map holds
the room's four walls."""
import os
import sys
import time
import unittest

import rospy
import rostest
from line_map_msgs.msg import LineMap, LineSegmentArray, MapQuality

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402


class CheckNodeVariants(unittest.TestCase):
    def test_nodes_run_the_pipeline(self):
        bag, _, _ = lt.simulate("square_room", 3, 60, "node_variants_")
        segments = lt.Collector("line_segments", LineSegmentArray)
        maps = lt.Collector("line_map", LineMap)
        qualities = lt.Collector("map_quality", MapQuality)
        time.sleep(1.0)
        lt.play(bag, 4)
        self.assertTrue(lt.wait_for(lambda: maps.messages and qualities.messages, 20.0),
                        "line_map: %d, map_quality: %d messages" % (len(maps.messages), len(qualities.messages)))
        self.assertTrue(segments.messages, "no line_segments from line_extraction_node")
        final = maps.messages[-1][1]
        print("node variants: %d line_segments messages, %d map segments, quality %.2f %%"
              % (len(segments.messages), len(final.segments), qualities.messages[-1][1].quality))
        self.assertEqual(final.header.frame_id, "map")
        self.assertGreaterEqual(len(final.segments), 4, "a square room has four walls")
        self.assertGreater(qualities.messages[-1][1].quality, 0.0)


if __name__ == "__main__":
    rospy.init_node("check_node_variants")
    rostest.rosrun("line_map_eval", "check_node_variants", CheckNodeVariants)

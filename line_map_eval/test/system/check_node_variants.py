#!/usr/bin/python3
"""Rostest checker (test/node_variants.test): the three stand-alone nodes run the pipeline on a
short simulated square room: line_segments, line_map and map_quality appear, and the map holds
the room's four walls."""
import os
import sys
import unittest

import rospy
import rostest

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402


class CheckNodeVariants(unittest.TestCase):
    def test_nodes_run_the_pipeline(self):
        bag, _, _ = lt.simulate("square_room", 3, 60, "node_variants_")
        run = lt.BagRun(bag, 4)
        final_map = run.play()  # waits for the map_quality of the final map too
        quality = run.quality_of(final_map)
        self.assertTrue(run.segments.messages, "no line_segments from line_extraction_node")
        print("node variants: %d line_segments messages, %d map segments, quality %.2f %%"
              % (len(run.segments.messages), len(final_map.segments), quality.quality))
        self.assertEqual(final_map.header.frame_id, "map")
        self.assertGreaterEqual(len(final_map.segments), 4, "a square room has four walls")
        self.assertGreater(quality.quality, 0.0)


if __name__ == "__main__":
    rospy.init_node("check_node_variants")
    rostest.rosrun("line_map_eval", "check_node_variants", CheckNodeVariants)

#!/usr/bin/python3
"""Rostest checker (eval_nodelet.test): plays a simulated office bag through linemap.launch and
checks the evaluator's outputs before and after the loop closure."""
import os
import subprocess
import sys
import tempfile
import unittest

import rospkg
import rospy
import rostest
from line_map_msgs.srv import Evaluate
from nav_msgs.msg import OccupancyGrid

sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), "system"))
import linemap_testing as lt  # noqa: E402


class CheckEval(unittest.TestCase):
    def test_map_quality_for_a_simulated_run(self):
        root = os.path.join(rospkg.RosPack().get_path("line_map_eval"), "..")
        bag = os.path.join(tempfile.mkdtemp(prefix="eval_nodelet_"), "office.bag")
        sim = subprocess.run(["rosrun", "line_map_eval", "simulate_world",
                              os.path.join(root, "config", "worlds", "office.yaml"), bag,
                              "--seed", "5", "--scans", "200", "--no-progress"],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=120)
        self.assertEqual(sim.returncode, 0, sim.stdout.decode(errors="replace"))

        grids = []
        rospy.Subscriber("lookup_table", OccupancyGrid, grids.append)
        # Plays the sensor topics, waits until the merger has finished with the last scan, then
        # publishes the bag's trajectory itself (a message at the very end of a bag can be lost when
        # rosbag play exits) and waits for the adjusted map and its map_quality: events, not windows.
        run = lt.BagRun(bag, 8)
        map_before = run.play()
        before = run.quality_of(map_before)
        adjusted = run.close_loop()
        final = run.quality_of(adjusted)
        self.assertEqual(final.header.frame_id, "map")
        self.assertGreater(final.segment_count, 10)
        self.assertGreater(final.quality, 50.0)
        self.assertLessEqual(final.quality, 100.0)
        self.assertGreater(final.error, 0.0)
        self.assertLess(final.error, 0.05)
        self.assertGreater(final.longest_length, final.mean_length)
        self.assertGreater(final.mean_length, final.shortest_length)
        rospy.loginfo("quality before the loop closure %.2f %%, after %.2f %%", before.quality, final.quality)

        lt.wait_until(lambda: any(g.header.stamp == adjusted.header.stamp for g in grids),
                      "the lookup_table published with the adjusted map's map_quality",
                      lambda: "%d lookup_table messages" % len(grids), run.limit)
        grid = grids[-1]
        self.assertEqual(grid.header.frame_id, "map")
        self.assertEqual(len(grid.data), grid.info.width * grid.info.height)
        self.assertEqual(max(grid.data), 100, "cells holding a scan point must be certain")
        self.assertGreaterEqual(min(grid.data), 0)

        rospy.wait_for_service("line_map_eval/evaluate", timeout=run.limit)
        evaluate = rospy.ServiceProxy("line_map_eval/evaluate", Evaluate)
        res = evaluate()
        self.assertTrue(res.success, res.message)
        self.assertAlmostEqual(res.quality.quality, final.quality, delta=1e-6)
        # A given map is scored against the same scans: the latest map scores the same, and the map
        # from before the loop closure scores lower against the corrected scans.
        given = evaluate(use_given_map=True, map=adjusted)
        self.assertTrue(given.success, given.message)
        self.assertAlmostEqual(given.quality.quality, final.quality, delta=1e-6)
        old = evaluate(use_given_map=True, map=map_before)
        self.assertTrue(old.success, old.message)
        rospy.loginfo("map before the loop closure against the corrected scans: %.2f %%", old.quality.quality)
        self.assertGreater(final.quality, old.quality.quality + 20.0,
                           "the loop closure must make the map fit the corrected scans far better")


if __name__ == "__main__":
    rospy.init_node("check_eval")
    rostest.rosrun("line_map_eval", "check_eval", CheckEval)

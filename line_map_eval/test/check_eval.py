#!/usr/bin/python3
"""Rostest checker (eval_nodelet.test): plays a simulated office bag through linemap.launch and
checks the evaluator's outputs before and after the loop closure."""
import os
import subprocess
import tempfile
import time
import unittest

import rospkg
import rospy
import rostest
from line_map_msgs.msg import LineMap, MapQuality
from line_map_msgs.srv import Evaluate
from nav_msgs.msg import OccupancyGrid, Path


class CheckEval(unittest.TestCase):
    def test_map_quality_for_a_simulated_run(self):
        root = os.path.join(rospkg.RosPack().get_path("line_map_eval"), "..")
        bag = os.path.join(tempfile.mkdtemp(prefix="eval_nodelet_"), "office.bag")
        sim = subprocess.run(["rosrun", "line_map_eval", "simulate_world",
                              os.path.join(root, "config", "worlds", "office.yaml"), bag,
                              "--seed", "5", "--scans", "200", "--no-progress"],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=120)
        self.assertEqual(sim.returncode, 0, sim.stdout.decode(errors="replace"))

        qualities, grids, paths, maps = [], [], [], []
        rospy.Subscriber("line_map", LineMap, maps.append)
        rospy.Subscriber("map_quality", MapQuality, lambda m: qualities.append((len(paths), m)))
        rospy.Subscriber("lookup_table", OccupancyGrid, grids.append)
        rospy.Subscriber("optimized_trajectory", Path, paths.append)
        time.sleep(1.0)
        play = subprocess.run(["rosbag", "play", "--clock", "--quiet", "--rate", "8", bag],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=240)
        self.assertEqual(play.returncode, 0, play.stdout.decode(errors="replace"))
        deadline = time.time() + 30.0
        while time.time() < deadline and not (paths and any(n > 0 for n, _ in qualities)):
            time.sleep(0.1)

        self.assertTrue(paths, "no optimized_trajectory in the bag")
        self.assertTrue(qualities, "no map_quality published")
        before = [m for n, m in qualities if n == 0]
        after = [m for n, m in qualities if n > 0]
        self.assertTrue(after, "no map_quality after the optimized_trajectory")
        final = after[-1]
        self.assertEqual(final.header.frame_id, "map")
        self.assertGreater(final.segment_count, 10)
        self.assertGreater(final.quality, 50.0)
        self.assertLessEqual(final.quality, 100.0)
        self.assertGreater(final.error, 0.0)
        self.assertLess(final.error, 0.05)
        self.assertGreater(final.longest_length, final.mean_length)
        self.assertGreater(final.mean_length, final.shortest_length)
        if before:
            rospy.loginfo("quality before the loop closure %.2f %%, after %.2f %%", before[-1].quality, final.quality)

        self.assertTrue(grids, "no lookup_table published")
        grid = grids[-1]
        self.assertEqual(grid.header.frame_id, "map")
        self.assertEqual(len(grid.data), grid.info.width * grid.info.height)
        self.assertEqual(max(grid.data), 100, "cells holding a scan point must be certain")
        self.assertGreaterEqual(min(grid.data), 0)

        rospy.wait_for_service("line_map_eval/evaluate", timeout=10.0)
        evaluate = rospy.ServiceProxy("line_map_eval/evaluate", Evaluate)
        res = evaluate()
        self.assertTrue(res.success, res.message)
        self.assertAlmostEqual(res.quality.quality, final.quality, delta=1e-6)
        # A given map is scored against the same scans: the latest map scores the same, and the map
        # from before the loop closure scores lower against the corrected scans.
        self.assertTrue(maps, "no line_map received")
        given = evaluate(use_given_map=True, map=maps[-1])
        self.assertTrue(given.success, given.message)
        self.assertAlmostEqual(given.quality.quality, final.quality, delta=1e-6)
        before_closure = [m for m in maps if m.header.stamp < paths[-1].header.stamp]
        if before_closure:
            old = evaluate(use_given_map=True, map=before_closure[-1])
            self.assertTrue(old.success, old.message)
            rospy.loginfo("map before the loop closure against the corrected scans: %.2f %%", old.quality.quality)
            self.assertGreater(final.quality, old.quality.quality + 20.0,
                               "the loop closure must make the map fit the corrected scans far better")


if __name__ == "__main__":
    rospy.init_node("check_eval")
    rostest.rosrun("line_map_eval", "check_eval", CheckEval)

#!/usr/bin/python3
"""Rostest checker of the whole pipeline: simulates a world into a bag (line_map_eval's
simulate_world), plays it on simulated time through the extraction and merging nodelets, and
checks that a line_map is built and that the optimized_trajectory at the end of the bag moves it."""
import math
import os
import subprocess
import tempfile
import time
import unittest

import rospkg
import rospy
import rostest
from line_map_msgs.msg import LineMap
from nav_msgs.msg import Path


def endpoints(m):
    return [(s.id, s.segment.start.x, s.segment.start.y, s.segment.end.x, s.segment.end.y) for s in m.segments]


class CheckPipeline(unittest.TestCase):
    def test_bag_through_extraction_and_merging(self):
        root = os.path.join(rospkg.RosPack().get_path("line_map_merging"), "..")
        world = os.path.join(root, "config", "worlds", "square_room.yaml")
        bag = os.path.join(tempfile.mkdtemp(), "square_room.bag")
        sim = subprocess.run(["rosrun", "line_map_eval", "simulate_world", world, bag, "--seed", "3",
                              "--scans", "120", "--no-progress"], stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, timeout=120)
        self.assertEqual(sim.returncode, 0, "simulate_world failed:\n" + sim.stdout.decode(errors="replace"))

        maps, paths = [], []
        rospy.Subscriber("line_map", LineMap, lambda m: maps.append((len(paths), m)))
        rospy.Subscriber("optimized_trajectory", Path, paths.append)
        time.sleep(1.0)
        play = subprocess.run(["rosbag", "play", "--clock", "--quiet", "--rate", "4", bag],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=240)
        self.assertEqual(play.returncode, 0, play.stdout.decode(errors="replace"))
        deadline = time.time() + 20.0
        while time.time() < deadline and not (paths and maps and maps[-1][0] > 0):
            time.sleep(0.1)

        self.assertTrue(paths, "no optimized_trajectory in the bag")
        before = [m for n, m in maps if n == 0]
        after = [m for n, m in maps if n > 0]
        self.assertTrue(before, "no line_map before the loop closure")
        self.assertTrue(after, "no line_map after the optimized_trajectory")
        b, a = before[-1], after[-1]
        self.assertEqual(b.header.frame_id, "map")
        self.assertGreater(b.keyframes, 5)
        self.assertGreaterEqual(len(b.segments), 4, "a square room has at least four walls")
        self.assertGreater(b.original_segments, len(b.segments), "segments of successive keyframes must merge")
        # A scan still in the pipeline may land after the trajectory: at most one more keyframe.
        self.assertIn(a.keyframes - b.keyframes, (0, 1))
        # The loop closure moves the map by the odometry drift, far more than merging one keyframe would.
        old = {s.id: s.segment for s in b.segments}
        shift = 0.0
        for s in a.segments:
            if s.id in old:
                o = old[s.id]
                shift = max(shift, math.hypot(s.segment.start.x - o.start.x, s.segment.start.y - o.start.y),
                            math.hypot(s.segment.end.x - o.end.x, s.segment.end.y - o.end.y))
        print("largest endpoint shift by the optimized_trajectory: %.3f m" % shift)
        self.assertGreater(shift, 0.05, "the optimized_trajectory did not move the map\n" + sim.stdout.decode())


if __name__ == "__main__":
    rospy.init_node("check_pipeline")
    rostest.rosrun("line_map_merging", "check_pipeline", CheckPipeline)

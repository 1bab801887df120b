#!/usr/bin/python3
"""Rostest checker of the whole pipeline: simulates a world into a bag (line_map_eval's
simulate_world), plays it on simulated time through the extraction and merging nodelets, and
checks that a line_map is built and that the bag's optimized_trajectory moves it."""
import math
import os
import subprocess
import sys
import tempfile
import unittest

import rospkg
import rospy
import rostest

sys.path.insert(0, os.path.join(rospkg.RosPack().get_path("line_map_eval"), "test", "system"))
import linemap_testing as lt  # noqa: E402


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

        # The checker plays the sensor topics, waits until the merger has finished with the last scan
        # (line_map_eval's shared rostest helpers: events, not windows), then publishes the bag's
        # trajectory itself: a message at the very end of a bag can be lost when rosbag play exits.
        run = lt.BagRun(bag, 4, evaluator=False)
        b = run.play()
        a = run.close_loop()
        self.assertEqual(b.header.frame_id, "map")
        self.assertGreater(b.keyframes, 5)
        self.assertGreaterEqual(len(b.segments), 4, "a square room has at least four walls")
        self.assertGreater(b.original_segments, len(b.segments), "segments of successive keyframes must merge")
        # The merger had finished with every scan before the trajectory: no keyframe comes in between.
        self.assertEqual(a.keyframes, b.keyframes)
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

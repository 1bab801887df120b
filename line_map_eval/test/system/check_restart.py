#!/usr/bin/python3
"""Rostest checker (test/restart.test): builds a map from a simulated bag in a pipeline started
with roslaunch, saves it (~save_map), applies the bag's optimized_trajectory, then stops the
pipeline, starts a new one, loads the saved map (~load_map) and applies the same trajectory. Both
adjusted maps must agree endpoint by endpoint within 1e-6 m."""
import os
import signal
import subprocess
import sys
import tempfile
import unittest

import rospy
import rostest
from line_map_msgs.srv import LoadMap, SaveMap
from nav_msgs.msg import Path

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402


class Pipeline:
    """launch/linemap.launch (no evaluator) as a roslaunch child on the test's master."""

    def __init__(self, log):
        self.proc = subprocess.Popen(["roslaunch", os.path.join(lt.repo_root(), "launch", "linemap.launch"),
                                      "evaluate:=false", "output:=log"], stdout=log, stderr=subprocess.STDOUT,
                                     start_new_session=True)
        rospy.wait_for_service("/line_map_merging/save_map", timeout=60.0)

    def stop(self):
        self.proc.send_signal(signal.SIGINT)
        try:
            self.proc.wait(30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        # The old services must be gone before the new pipeline is waited for.
        lt.wait_until(lambda: not self._service_up(), "the stopped pipeline's save_map service to go",
                      lambda: "still registered", 60.0)

    @staticmethod
    def _service_up():
        try:
            rospy.wait_for_service("/line_map_merging/save_map", timeout=0.2)
            return True
        except rospy.ROSException:
            return False


def endpoints(m):
    return sorted((s.segment.start.x, s.segment.start.y, s.segment.end.x, s.segment.end.y) for s in m.segments)


def publish_trajectory(trajectory, limit):
    # Not latched: the second pipeline must not receive the first trajectory before its load_map.
    pub = rospy.Publisher("optimized_trajectory", Path, queue_size=1)
    lt.wait_until(lambda: pub.get_num_connections() > 0, "a subscriber of optimized_trajectory",
                  lambda: "none", limit)
    pub.publish(trajectory)
    return pub


class CheckRestart(unittest.TestCase):
    def test_saved_map_adjusts_like_the_live_one(self):
        bag, _, _ = lt.simulate("square_room", 3, 120, "restart_")
        trajectory = lt.bag_trajectories(bag)[-1]
        map_file = os.path.join(os.path.dirname(bag), "saved.yaml")
        log = open(os.path.join(lt.artifact_dir(), "restart_roslaunch.log"), "w")
        run = lt.BagRun(bag, 4, evaluator=False)
        maps, limit = run.maps, run.limit

        first = Pipeline(log)
        try:
            saved = run.play()
            res = rospy.ServiceProxy("/line_map_merging/save_map", SaveMap)(map_file)
            self.assertTrue(res.success, res.message)
            n = len(maps.messages)
            publish_trajectory(trajectory, limit)
            live = lt.wait_for_new_map(maps, n, "the line_map adjusted to the optimized_trajectory", limit)
        finally:
            first.stop()

        second = Pipeline(log)
        try:
            n = len(maps.messages)
            res = rospy.ServiceProxy("/line_map_merging/load_map", LoadMap)(map_file)
            self.assertTrue(res.success, res.message)
            loaded = lt.wait_for_new_map(maps, n, "the line_map of load_map", limit)
            self.assertEqual(len(loaded.segments), len(saved.segments), "load_map did not restore the map")
            n = len(maps.messages)
            publish_trajectory(trajectory, limit)
            restarted = lt.wait_for_new_map(maps, n, "the line_map adjusted to the optimized_trajectory "
                                            "(restarted)", limit)
        finally:
            second.stop()

        a, b = endpoints(live), endpoints(restarted)
        shift = max(max(abs(u - v) for u, v in zip(p, q)) for p, q in zip(a, b)) if a and len(a) == len(b) else -1
        print("restart: %d segments saved, %d adjusted live, %d adjusted after the restart, largest endpoint "
              "difference %.3g m" % (len(saved.segments), len(a), len(b), shift))
        self.assertNotEqual(endpoints(saved), a, "the trajectory did not change the map: the comparison is void")
        self.assertEqual(len(a), len(b))
        for p, q in zip(a, b):
            for u, v in zip(p, q):
                self.assertAlmostEqual(u, v, delta=1e-6)


if __name__ == "__main__":
    rospy.init_node("check_restart")
    rostest.rosrun("line_map_eval", "check_restart", CheckRestart)

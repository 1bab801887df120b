#!/usr/bin/python3
"""Rostest checker (bad_input.test): bad input to the merging nodelet, each case counted in
/diagnostics while the nodelet keeps merging the good input around it; then a burst of
trajectories, of which the last decides the map."""
import os
import sys
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped
from line_map_msgs.msg import LineMap
from nav_msgs.msg import Path

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
from check_merging import LIMIT, STEP, connect_to_merger, segments_seen_from, transform  # noqa: E402


def pose(stamp, x, y=0.0, w=1.0):
    p = PoseStamped()
    p.header.stamp = stamp
    p.header.frame_id = "map"
    p.pose.position.x = x
    p.pose.position.y = y
    p.pose.orientation.w = w
    return p


class CheckBadInput(unittest.TestCase):
    def setUp(self):
        self.maps, self.diagnostics = [], []
        rospy.Subscriber("line_map", LineMap, self.maps.append)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.diagnostics.append)
        connect_to_merger(self)

    def counters(self, wait_for=None, timeout=LIMIT):
        """The latest merger diagnostics as a dict; waits until `wait_for(dict)` holds."""
        deadline = time.time() + timeout
        c = {}
        while time.time() < deadline:
            for array in reversed(self.diagnostics):
                found = [s for s in array.status if "line map merging" in s.name]
                if found:
                    c = {kv.key: kv.value for kv in found[0].values}
                    break
            if c and (wait_for is None or wait_for(c)):
                return c
            time.sleep(0.2)
        return c

    def test_bad_input(self):
        base = rospy.Time.now()
        # 1. A trajectory before any scan: nothing to adjust, its pose counted as unmatched.
        path = Path()
        path.header.frame_id = "map"
        path.header.stamp = base
        path.poses.append(pose(base, 0.0))
        self.path_pub.publish(path)
        c = self.counters(lambda c: int(c.get("unmatched trajectory poses", 0)) >= 1)
        self.assertEqual(int(c.get("unmatched trajectory poses", -1)), 1, c)
        self.assertEqual(int(c.get("keyframes", -1)), 0, c)

        # 2. Segments in a frame no tf reaches: dropped after the tf timeout, counted.
        lost = segments_seen_from(0.0, base)
        lost.header.frame_id = "nowhere"
        self.pub.publish(lost)
        c = self.counters(lambda c: int(c.get("dropped scans", 0)) >= 1)
        self.assertGreaterEqual(int(c.get("dropped scans", 0)), 1, c)

        # 3. A zero stamp: dropped and counted.
        self.pub.publish(segments_seen_from(0.0, rospy.Time(0)))
        c = self.counters(lambda c: int(c.get("zero-stamp segments", 0)) >= 1)
        self.assertEqual(int(c.get("zero-stamp segments", -1)), 1, c)

        # 4. Good keyframes, the tf of the second arriving 0.3 s after its segments (within the
        # filter's wait): both merged.
        stamps = [base + rospy.Duration(1.0 + 0.1 * i) for i in range(3)]
        for i, stamp in enumerate(stamps):
            msg = segments_seen_from(STEP * i, stamp)
            if i == 1:
                self.pub.publish(msg)
                time.sleep(0.3)
                self.tf.sendTransform(transform("map", "base_link", stamp, STEP * i, 0.0, 0.0))
            else:
                self.tf.sendTransform(transform("map", "base_link", stamp, STEP * i, 0.0, 0.0))
                time.sleep(0.05)
                self.pub.publish(msg)
            time.sleep(0.2)
        deadline = time.time() + LIMIT
        while time.time() < deadline and not (self.maps and self.maps[-1].keyframes == 3):
            time.sleep(0.05)
        self.assertTrue(self.maps and self.maps[-1].keyframes == 3,
                        "the late-tf keyframe was not merged: %s" % (self.maps[-1] if self.maps else None))

        # 5. A trajectory with a duplicate stamp, a stray pose and a non-normalised quaternion: the
        # usable poses move the map, the others are counted.
        n = len(self.maps)
        path = Path()
        path.header.frame_id = "map"
        path.header.stamp = stamps[-1]
        for i, stamp in enumerate(stamps):
            path.poses.append(pose(stamp, STEP * i, 0.5))
        path.poses.append(pose(stamps[0], 0.0, 0.5))  # duplicate stamp, same pose
        path.poses.append(pose(base + rospy.Duration(500.0), 9.0))  # matches no keyframe
        path.poses.append(pose(stamps[1], 0.0, 0.0, w=3.0))  # not a rotation
        self.path_pub.publish(path)
        deadline = time.time() + LIMIT
        while time.time() < deadline and len(self.maps) == n:
            time.sleep(0.05)
        self.assertGreater(len(self.maps), n, "no line_map after the trajectory")
        ys = sorted(0.5 * (s.segment.start.y + s.segment.end.y) for s in self.maps[-1].segments)
        self.assertEqual(len(ys), 2)
        self.assertAlmostEqual(ys[0], -1.5, delta=1e-6)  # the walls at y = -2 and 2 moved by 0.5 m
        self.assertAlmostEqual(ys[1], 2.5, delta=1e-6)
        c = self.counters(lambda c: int(c.get("bad trajectory poses", 0)) >= 1)
        self.assertEqual(int(c.get("bad trajectory poses", -1)), 1, c)
        self.assertEqual(int(c.get("unmatched trajectory poses", -1)), 2, c)
        self.assertEqual(int(c.get("keyframes", -1)), 3, c)

        # 6. Trajectories back to back, each arriving while the previous one may still be adjusting
        # (the subscriber keeps 2, the nodelet adjusts one at a time): the last one decides the map.
        adjustments = int(c.get("adjustments", 0))
        for k, dy in enumerate([0.6, 0.7, 0.8, 0.9, 1.0]):
            burst = Path()
            burst.header.frame_id = "map"
            burst.header.stamp = stamps[-1] + rospy.Duration(0.001 * (k + 1))
            burst.poses = [pose(stamp, STEP * i, dy) for i, stamp in enumerate(stamps)]
            self.path_pub.publish(burst)

        def walls_moved_by(dy):
            if not self.maps:
                return False
            ys = sorted(0.5 * (s.segment.start.y + s.segment.end.y) for s in self.maps[-1].segments)
            return len(ys) == 2 and abs(ys[0] - (-2.0 + dy)) < 1e-6 and abs(ys[1] - (2.0 + dy)) < 1e-6

        deadline = time.time() + LIMIT
        while time.time() < deadline and not walls_moved_by(1.0):
            time.sleep(0.05)
        self.assertTrue(walls_moved_by(1.0), "the last trajectory of a burst did not decide the map: %s" %
                        [(s.segment.start.y, s.segment.end.y) for s in self.maps[-1].segments])
        c = self.counters(lambda c: int(c.get("adjustments", 0)) > adjustments)
        self.assertGreater(int(c.get("adjustments", 0)), adjustments, c)
        self.assertLessEqual(int(c.get("adjustments", 0)), adjustments + 5, c)
        self.assertEqual(int(c.get("keyframes", -1)), 3, c)


if __name__ == "__main__":
    rospy.init_node("check_bad_input")
    rostest.rosrun("line_map_merging", "check_bad_input", CheckBadInput, sys.argv)

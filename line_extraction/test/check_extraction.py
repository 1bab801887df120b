#!/usr/bin/python3
"""Rostest checker: publishes a full-turn LaserScan of a square room and checks the
line_extraction nodelet's segments (the scan's stamp and frame, the four walls)."""
import math
import sys
import unittest

import rospy
import rostest
from line_map_msgs.msg import LineSegmentArray
from sensor_msgs.msg import LaserScan
from visualization_msgs.msg import MarkerArray

HALF = 3.0  # room |x|, |y| <= 3 m
POSE = (0.4, -0.3, 0.2)  # laser x, y, yaw in the room
BEAMS = 360


def room_scan(stamp):
    scan = LaserScan()
    scan.header.stamp = stamp
    scan.header.frame_id = "test_laser"
    scan.angle_min = -math.pi
    scan.angle_increment = 2.0 * math.pi / BEAMS
    scan.angle_max = scan.angle_min + (BEAMS - 1) * scan.angle_increment
    scan.range_min = 0.05
    scan.range_max = 20.0
    cx, cy, yaw = POSE
    for i in range(BEAMS):
        a = yaw + scan.angle_min + i * scan.angle_increment
        dx, dy = math.cos(a), math.sin(a)
        t = float("inf")
        if dx > 1e-12:
            t = min(t, (HALF - cx) / dx)
        if dx < -1e-12:
            t = min(t, (-HALF - cx) / dx)
        if dy > 1e-12:
            t = min(t, (HALF - cy) / dy)
        if dy < -1e-12:
            t = min(t, (-HALF - cy) / dy)
        scan.ranges.append(t)
    return scan


def walls():
    """(angle, radius) of the four walls in the laser frame."""
    cx, cy, yaw = POSE
    wrap = lambda a: math.atan2(math.sin(a), math.cos(a))
    return [(wrap(-yaw), HALF - cx), (wrap(math.pi - yaw), HALF + cx),
            (wrap(math.pi / 2 - yaw), HALF - cy), (wrap(-math.pi / 2 - yaw), HALF + cy)]


def wall_errors(segments):
    """For each wall, whether some segment lies on it (1 cm, 0.01 rad)."""
    found = []
    for angle, radius in walls():
        near = [s for s in segments
                if abs(s.radius - radius) < 0.01 and abs(math.remainder(s.angle - angle, 2 * math.pi)) < 0.01]
        found.append(near[0] if near else None)
    return found


# Bound of the wait for every extractor's answer (wall time; the wait ends when all answered).
LIMIT = 120.0


class CheckExtraction(unittest.TestCase):
    """Namespaces (private parameters, lists): `full` must find the four walls,
    `light` must answer each scan with its stamp and frame, `idle` (bad
    parameters) must not advertise line_segments at all."""

    def collect(self, namespaces):
        received = {ns: [] for ns in namespaces}
        markers = {ns: [] for ns in namespaces}
        subs = []
        for ns in namespaces:
            subs.append(rospy.Subscriber(ns + "/line_segments", LineSegmentArray, received[ns].append))
            subs.append(rospy.Subscriber(ns + "/line_segments_markers", MarkerArray, markers[ns].append))
        pub = rospy.Publisher("scan", LaserScan, queue_size=1)
        stamp = rospy.Time(1234, 567000000)
        # Interleaved unusable scans (zero angle_increment) are skipped with a warning.
        bad = room_scan(rospy.Time(999, 0))
        bad.angle_increment = 0.0
        # Resent until every namespace answered (the event): the nodelets load one after another.
        deadline = rospy.get_time() + LIMIT
        while rospy.get_time() < deadline and not rospy.is_shutdown():
            if all(received[ns] and markers[ns] for ns in namespaces):
                break
            pub.publish(bad)
            rospy.sleep(0.1)
            pub.publish(room_scan(stamp))
            rospy.sleep(0.1)
        for ns in namespaces:
            for msg in received[ns]:
                self.assertEqual(msg.header.stamp, stamp, "%s answered an unusable scan" % ns)
        return stamp, received, markers

    def test_segments_of_a_square_room(self):
        full = rospy.get_param("~full", ["srg"])
        light = rospy.get_param("~light", [])
        stamp, received, markers = self.collect(full + light)
        for ns in full + light:
            self.assertTrue(received[ns], "waited %.0f s for a LineSegmentArray on %s/line_segments; arrived on: %s"
                            % (LIMIT, ns, [n for n in full + light if received[n]]))
            msg = received[ns][0]
            self.assertEqual(msg.header.stamp, stamp, ns)
            self.assertEqual(msg.header.frame_id, "test_laser", ns)
            self.assertTrue(markers[ns], "no MarkerArray on %s/line_segments_markers" % ns)
            m = markers[ns][0]
            self.assertEqual(len(m.markers), 3, ns)  # lines, start points, end points
            for marker in m.markers:
                self.assertEqual(marker.header.frame_id, "test_laser", ns)
                self.assertEqual(marker.header.stamp, stamp, ns)
        for ns in full:
            msg = received[ns][0]
            self.assertGreaterEqual(len(msg.segments), 4, ns)
            for wall, s in zip(walls(), wall_errors(msg.segments)):
                self.assertIsNotNone(s, "%s: no segment on the wall angle %.3f radius %.3f" % (ns, wall[0], wall[1]))
                self.assertGreater(s.num_points, 10, ns)
                self.assertGreater(s.covariance[0], 0.0, ns)
                self.assertGreater(s.covariance[3], 0.0, ns)
                self.assertAlmostEqual(s.covariance[1], s.covariance[2])
            m = markers[ns][0]
            self.assertEqual(len(m.markers[0].points), 2 * len(msg.segments), ns)
            self.assertEqual(len(m.markers[1].points), len(msg.segments), ns)
        # Every other nodelet of the manager has advertised by now: the idle ones
        # (bad parameters) must not have.
        topics = [t for t, _ in rospy.get_published_topics()]
        for ns in rospy.get_param("~idle", []):
            self.assertNotIn("/" + ns + "/line_segments", topics)
        self.assertIn("/" + (full + light)[0] + "/line_segments", topics)


if __name__ == "__main__":
    rospy.init_node("check_extraction")
    rostest.rosrun("line_extraction", "check_extraction", CheckExtraction, sys.argv)

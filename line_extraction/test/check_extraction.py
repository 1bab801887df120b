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


class CheckExtraction(unittest.TestCase):
    def test_segments_of_a_square_room(self):
        received = []
        markers = []
        rospy.Subscriber("line_segments", LineSegmentArray, received.append)
        rospy.Subscriber("line_segments_markers", MarkerArray, markers.append)
        pub = rospy.Publisher("scan", LaserScan, queue_size=1)
        stamp = rospy.Time(1234, 567000000)
        deadline = rospy.get_time() + 30.0
        while not received and rospy.get_time() < deadline and not rospy.is_shutdown():
            pub.publish(room_scan(stamp))
            rospy.sleep(0.2)
        self.assertTrue(received, "no LineSegmentArray on line_segments within 30 s")
        msg = received[0]
        self.assertEqual(msg.header.stamp, stamp)
        self.assertEqual(msg.header.frame_id, "test_laser")
        self.assertGreaterEqual(len(msg.segments), 4)
        for angle, radius in walls():
            near = [s for s in msg.segments
                    if abs(s.radius - radius) < 0.01 and abs(math.remainder(s.angle - angle, 2 * math.pi)) < 0.01]
            self.assertTrue(near, "no segment on the wall angle %.3f radius %.3f" % (angle, radius))
            s = near[0]
            self.assertGreater(s.num_points, 10)
            self.assertGreater(s.covariance[0], 0.0)
            self.assertGreater(s.covariance[3], 0.0)
            self.assertAlmostEqual(s.covariance[1], s.covariance[2])
        # Markers: lines, start points, end points, in the scan's frame.
        deadline = rospy.get_time() + 10.0
        while not markers and rospy.get_time() < deadline:
            pub.publish(room_scan(stamp))
            rospy.sleep(0.2)
        self.assertTrue(markers, "no MarkerArray on line_segments_markers")
        self.assertEqual(len(markers[0].markers), 3)
        for m in markers[0].markers:
            self.assertEqual(m.header.frame_id, "test_laser")
            self.assertEqual(m.header.stamp, stamp)
        self.assertEqual(len(markers[0].markers[0].points), 2 * len(markers[0].markers[1].points))


if __name__ == "__main__":
    rospy.init_node("check_extraction")
    rostest.rosrun("line_extraction", "check_extraction", CheckExtraction, sys.argv)

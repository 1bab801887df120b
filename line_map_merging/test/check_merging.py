#!/usr/bin/python3
"""Rostest checker of the merging nodelet alone: publishes tf (map -> base_link -> laser) and
LineSegmentArrays of two corridor walls while driving along x, then checks line_map, the
adjustment by an optimized_trajectory, bad input, and the save/load/reset services."""
import math
import os
import tempfile
import time
import unittest

import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import Point, PoseStamped, TransformStamped
from line_map_msgs.msg import LineMap, LineSegment, LineSegmentArray
from line_map_msgs.srv import LoadMap, ResetMap, SaveMap
from nav_msgs.msg import Path
from visualization_msgs.msg import MarkerArray

MOUNT_X = 0.1  # base_link -> laser
STEP = 0.3     # m between scans (above the 0.2 m keyframe gate)
SCANS = 20
# Bound of every wait (wall time): each wait ends on its event (a map, a subscriber, a report).
# The .test files raise the merger's tf_timeout (a wall-clock wait here, no sim time) to 10 s, so
# that a segments message whose tf comes late on a loaded machine is not dropped.
LIMIT = 60.0
WALLS = [((-5.0, 2.0), (30.0, 2.0)), ((30.0, -2.0), (-5.0, -2.0))]  # opposite directions


def transform(parent, child, stamp, x, y, yaw):
    t = TransformStamped()
    t.header.stamp = stamp
    t.header.frame_id = parent
    t.child_frame_id = child
    t.transform.translation.x = x
    t.transform.translation.y = y
    t.transform.rotation.z = math.sin(yaw / 2)
    t.transform.rotation.w = math.cos(yaw / 2)
    return t


def segments_seen_from(x, stamp):
    """The walls within 3 m along x of the robot, in the laser frame (laser at x + MOUNT_X, 0, 0)."""
    msg = LineSegmentArray()
    msg.header.stamp = stamp
    msg.header.frame_id = "laser"
    lx = x + MOUNT_X
    for (ax, ay), (bx, by) in WALLS:
        lo, hi = max(min(ax, bx), x - 3.0), min(max(ax, bx), x + 3.0)
        s = LineSegment()
        sx, ex = (lo, hi) if bx > ax else (hi, lo)
        s.start = Point(sx - lx, ay, 0.0)
        s.end = Point(ex - lx, by, 0.0)
        msg.segments.append(s)
    return msg


def connect_to_merger(test):
    """tf broadcasters (with the static base_link -> laser), the line_segments and
    optimized_trajectory publishers on `test`, once the merging nodelet subscribes to both."""
    test.tf = tf2_ros.TransformBroadcaster()
    test.static_tf = tf2_ros.StaticTransformBroadcaster()
    test.static_tf.sendTransform(transform("base_link", "laser", rospy.Time(0), MOUNT_X, 0.0, 0.0))
    test.pub = rospy.Publisher("line_segments", LineSegmentArray, queue_size=50)
    test.path_pub = rospy.Publisher("optimized_trajectory", Path, queue_size=5)
    deadline = time.time() + LIMIT
    while test.pub.get_num_connections() == 0 or test.path_pub.get_num_connections() == 0:
        test.assertLess(time.time(), deadline, "waited %.0f s for the merging nodelet to subscribe; line_segments "
                        "subscribers %d, optimized_trajectory subscribers %d" % (
                            LIMIT, test.pub.get_num_connections(), test.path_pub.get_num_connections()))
        time.sleep(0.1)


class CheckMerging(unittest.TestCase):
    def setUp(self):
        self.maps = []
        rospy.Subscriber("line_map", LineMap, self.maps.append)
        self.markers = []
        rospy.Subscriber("line_map_markers", MarkerArray, self.markers.append)
        connect_to_merger(self)

    def wait_for(self, predicate, what, timeout=None):
        timeout = LIMIT if timeout is None else timeout
        deadline = time.time() + timeout
        while time.time() < deadline:
            if self.maps and predicate(self.maps[-1]):
                return self.maps[-1]
            time.sleep(0.05)
        self.fail("waited %.0f s for %s; arrived: %d line_map messages, the last: %s"
                  % (timeout, what, len(self.maps), self.maps[-1] if self.maps else None))

    def wall_ys(self, m):
        return sorted(0.5 * (s.segment.start.y + s.segment.end.y) for s in m.segments)

    def test_merging_adjustment_and_services(self):
        stamps = []
        base = rospy.Time.now()
        for i in range(SCANS):
            stamp = base + rospy.Duration(0.1 * (i + 1))
            stamps.append(stamp)
            self.tf.sendTransform(transform("map", "base_link", stamp, STEP * i, 0.0, 0.0))
            self.pub.publish(segments_seen_from(STEP * i, stamp))
            time.sleep(0.05)
        m = self.wait_for(lambda m: m.keyframes == SCANS, "%d keyframes" % SCANS)
        self.assertEqual(m.header.frame_id, "map")
        self.assertEqual(m.original_segments, 2 * SCANS)
        self.assertEqual(len(m.segments), 2, "two walls, two segments")
        ys = self.wall_ys(m)
        self.assertAlmostEqual(ys[0], -2.0, delta=1e-6)
        self.assertAlmostEqual(ys[1], 2.0, delta=1e-6)
        upper = [s for s in m.segments if s.segment.start.y > 0][0]
        self.assertEqual(upper.merged_count, SCANS)
        self.assertAlmostEqual(upper.segment.start.x, -3.0, delta=1e-6)
        self.assertAlmostEqual(upper.segment.end.x, STEP * (SCANS - 1) + 3.0, delta=1e-6)
        self.assertAlmostEqual(upper.segment.angle, math.pi / 2, delta=1e-6)  # Hessian normal +y
        self.assertAlmostEqual(upper.segment.radius, 2.0, delta=1e-6)

        # Markers (subscribed, so published): segments, red start points, green end points.
        deadline = time.time() + LIMIT
        while not self.markers and time.time() < deadline:
            time.sleep(0.05)
        self.assertTrue(self.markers, "no line_map_markers although subscribed")
        by_ns = {mk.ns: mk for mk in self.markers[-1].markers if mk.action == mk.ADD}
        self.assertEqual(len(by_ns["segments"].points), 4)
        self.assertEqual((by_ns["start_points"].color.r, by_ns["start_points"].color.g), (1.0, 0.0))
        self.assertGreater(by_ns["end_points"].color.g, 0.5)
        self.assertEqual(by_ns["end_points"].color.r, 0.0)

        # Loop closure: every base pose 0.5 m further in +y. Every other pose only: the others
        # are corrected by interpolation. One pose matches no keyframe.
        path = Path()
        path.header.frame_id = "map"
        path.header.stamp = stamps[-1]
        for i, stamp in enumerate(stamps):
            if i % 2 == 1 and i != SCANS - 1:
                continue
            p = PoseStamped()
            p.header.stamp = stamp
            p.pose.position.x = STEP * i
            p.pose.position.y = 0.5
            p.pose.orientation.w = 1.0
            path.poses.append(p)
        stray = PoseStamped()
        stray.header.stamp = base + rospy.Duration(1000.0)
        stray.pose.orientation.w = 1.0
        path.poses.append(stray)
        self.path_pub.publish(path)
        m = self.wait_for(lambda m: abs(self.wall_ys(m)[1] - 2.5) < 1e-6, "the map to move 0.5 m")
        self.assertEqual(len(m.segments), 2)
        self.assertAlmostEqual(self.wall_ys(m)[0], -1.5, delta=1e-6)

        # Bad input never kills the nodelet: empty path, non-normalised quaternion, NaN segment.
        self.path_pub.publish(Path())
        bad = Path()
        bad.header.frame_id = "map"
        q = PoseStamped()
        q.header.stamp = stamps[0]
        q.pose.orientation.w = 2.0
        bad.poses.append(q)
        self.path_pub.publish(bad)
        stamp = base + rospy.Duration(0.1 * (SCANS + 1))
        self.tf.sendTransform(transform("map", "base_link", stamp, STEP * SCANS, 0.5, 0.0))
        nan_scan = segments_seen_from(STEP * SCANS, stamp)
        nan_scan.segments[0].start.x = float("nan")
        nan_scan.segments[1].end = nan_scan.segments[1].start  # zero length
        self.pub.publish(nan_scan)
        m = self.wait_for(lambda m: m.keyframes == SCANS + 1, "the keyframe with bad segments")
        self.assertEqual(m.original_segments, 2 * SCANS)

        # Services: save, reset, load (bad then good).
        for name in ("line_map_merging/save_map", "line_map_merging/load_map", "line_map_merging/reset_map"):
            rospy.wait_for_service(name, timeout=LIMIT)
        save = rospy.ServiceProxy("line_map_merging/save_map", SaveMap)
        load = rospy.ServiceProxy("line_map_merging/load_map", LoadMap)
        reset = rospy.ServiceProxy("line_map_merging/reset_map", ResetMap)
        path_file = os.path.join(tempfile.mkdtemp(), "map.yaml")
        r = save(path_file)
        self.assertTrue(r.success, r.message)
        self.assertTrue(os.path.exists(path_file))
        r = reset()
        self.assertTrue(r.success, r.message)
        self.wait_for(lambda m: len(m.segments) == 0 and m.keyframes == 0, "the empty map")
        r = load(path_file + ".missing")
        self.assertFalse(r.success)
        self.assertIn(".missing", r.message)
        r = load(path_file)
        self.assertTrue(r.success, r.message)
        m = self.wait_for(lambda m: m.keyframes == SCANS + 1, "the loaded map")
        self.assertEqual(len(m.segments), 2)
        self.assertAlmostEqual(self.wall_ys(m)[1], 2.5, delta=1e-6)


if __name__ == "__main__":
    rospy.init_node("check_merging")
    rostest.rosrun("line_map_merging", "check_merging", CheckMerging)

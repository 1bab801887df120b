#!/usr/bin/python3
"""Rostest checker (bad_scans.test): bad LaserScans through the extraction nodelet. Unusable
geometry (angle_increment 0, negative or NaN, range_min > range_max, ranges and intensities of
different lengths) gets no output and counts as "rejected scans"; usable oddities (NaN, inf and
negative ranges, all readings invalid, no beams, one beam, 10^6 beams, angle_max inconsistent with
angle_min and angle_increment, a changed geometry, frame ids with and without a leading slash) get
an answer with the scan's stamp and frame. After every bad scan a good one must still be answered."""
import math
import os
import sys
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from line_map_msgs.msg import LineSegmentArray
from sensor_msgs.msg import LaserScan

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
from check_extraction import room_scan  # noqa: E402

# Bound of every wait (wall time); each wait ends on its event (an answer, a diagnostics report).
LIMIT = 60.0


def with_changes(scan, **fields):
    for k, v in fields.items():
        setattr(scan, k, v)
    return scan


class CheckBadScans(unittest.TestCase):
    def setUp(self):
        self.answers = []
        self.diagnostics = []
        rospy.Subscriber("line_segments", LineSegmentArray, self.answers.append)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.diagnostics.append)
        self.pub = rospy.Publisher("scan", LaserScan, queue_size=10)
        self.secs = 100

    def send(self, scan, wait=True):
        """Publishes `scan` with a fresh stamp; with `wait`, returns its answer (the event; LIMIT s
        bound the wait and fail the test), else its stamp."""
        self.secs += 1
        scan.header.stamp = rospy.Time(self.secs, 0)
        self.pub.publish(scan)
        if not wait:
            return scan.header.stamp
        deadline = time.time() + LIMIT
        while time.time() < deadline:
            answer = self.answer(scan.header.stamp)
            if answer is not None:
                return answer
            time.sleep(0.02)
        self.fail("waited %.0f s for the answer to the scan stamped %d; arrived: %d answers, the last stamped %s"
                  % (LIMIT, self.secs, len(self.answers),
                     self.answers[-1].header.stamp.secs if self.answers else "-"))

    def answer(self, stamp):
        return next((a for a in reversed(self.answers) if a.header.stamp == stamp), None)

    def counters(self):
        for array in reversed(self.diagnostics):
            for status in array.status:
                if "line extraction" in status.name:
                    return {kv.key: kv.value for kv in status.values}
        return {}

    def test_bad_scans(self):
        # Until the nodelet is up and subscribed, published scans go nowhere: resend until answered.
        deadline = time.time() + LIMIT
        while self.pub.get_num_connections() == 0 or not self.answers:
            self.assertLess(time.time(), deadline, "waited %.0f s for the nodelet to answer a good scan; "
                            "subscribers of scan: %d" % (LIMIT, self.pub.get_num_connections()))
            self.pub.publish(with_changes(room_scan(rospy.Time(1, 0))))
            time.sleep(0.2)
        nan, inf = float("nan"), float("inf")

        unusable = {
            "angle_increment 0": with_changes(room_scan(rospy.Time()), angle_increment=0.0),
            "angle_increment negative": with_changes(room_scan(rospy.Time()), angle_increment=-0.01),
            "angle_increment NaN": with_changes(room_scan(rospy.Time()), angle_increment=nan),
            "range_min > range_max": with_changes(room_scan(rospy.Time()), range_min=30.0, range_max=20.0),
            "intensities of another length": with_changes(room_scan(rospy.Time()), intensities=[1.0] * 7),
        }
        base = room_scan(rospy.Time())
        usable = {
            "NaN, inf and negative ranges": with_changes(
                room_scan(rospy.Time()),
                ranges=[(nan, inf, -inf, -1.0)[i % 4] if i % 3 == 0 else r for i, r in enumerate(base.ranges)]),
            "all readings invalid": with_changes(room_scan(rospy.Time()), ranges=[nan] * len(base.ranges)),
            "no beams": with_changes(room_scan(rospy.Time()), ranges=[]),
            "one beam": with_changes(room_scan(rospy.Time()), ranges=[2.0]),
            "10^6 beams": with_changes(room_scan(rospy.Time()), ranges=[3.0] * 1000000,
                                       angle_increment=2 * math.pi / 1000000, angle_min=-math.pi),
            "inconsistent angle_max": with_changes(room_scan(rospy.Time()), angle_max=0.5),
            "leading slash": with_changes(room_scan(rospy.Time()), header=base.header),
        }
        usable["leading slash"].header.frame_id = "/test_laser"
        for name, scan in unusable.items():
            frame = scan.header.frame_id
            # The nodelet takes its scans in order: once the good scan after it is answered, an answer
            # to the unusable one would have come.
            bad = self.send(scan, wait=False)
            good = self.send(room_scan(rospy.Time()))
            self.assertIsNone(self.answer(bad), "%s: the unusable scan was answered" % name)
            self.assertGreaterEqual(len(good.segments), 4, name)
            self.assertEqual(frame, "test_laser")
        for name, scan in usable.items():
            answer = self.send(scan)
            self.assertEqual(answer.header.frame_id, scan.header.frame_id, name)
            for s in answer.segments:
                self.assertTrue(all(math.isfinite(v) for v in (s.start.x, s.start.y, s.end.x, s.end.y)), name)
            self.send(room_scan(rospy.Time()))

        # The counters (diagnostics are published every second): wait for a report that has seen
        # every scan sent above.
        sent = 2 * (len(unusable) + len(usable)) + 1
        deadline = time.time() + LIMIT
        c = self.counters()
        while not (c and int(c.get("scans", 0)) >= sent):
            self.assertLess(time.time(), deadline, "waited %.0f s for diagnostics counting %d scans; the last: %s"
                            % (LIMIT, sent, c))
            time.sleep(0.1)
            c = self.counters()
        self.assertEqual(int(c.get("rejected scans", -1)), len(unusable), c)
        self.assertGreaterEqual(int(c.get("inconsistent angle_max", 0)), 1, c)
        # The geometry changed at least into and out of the one-beam, no-beam and 10^6-beam scans.
        self.assertGreaterEqual(int(c.get("geometry changes", 0)), 6, c)


if __name__ == "__main__":
    rospy.init_node("check_bad_scans")
    rostest.rosrun("line_extraction", "check_bad_scans", CheckBadScans, sys.argv)

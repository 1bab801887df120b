#!/usr/bin/python3
"""Rostest checker (test/scan_only_bag.test): a third-party bag holding nothing but a scan topic, its
frame id written with a leading slash (`/laser`) and no tf at all, through both ways README offers:
`replay.launch map_frame:=/laser` (the laser frame is the fixed frame) and `replay.launch
static_scan_tf:=true scan_frame:=/laser` (a static map -> laser transform: the robot taken as
standing still). Each must yield a line_map holding the room's four walls and a map_quality of it;
with static_scan_tf every scan is seen from the same pose, so the map has one keyframe."""
import math
import os
import signal
import subprocess
import sys
import tempfile
import unittest

import rosbag
import rospy
import rostest
from line_map_msgs.msg import LineMap, MapQuality
from sensor_msgs.msg import LaserScan

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402

SCANS = 100
PERIOD = 0.1  # s between scans
HALF = 2.0  # the room is 4 x 4 m, the laser 0.3 m off its centre


def room_range(angle):
    """Range from (0.3, 0.2) to the walls x = +-HALF, y = +-HALF along `angle`."""
    x0, y0 = 0.3, 0.2
    c, s = math.cos(angle), math.sin(angle)
    best = float("inf")
    for wall, d in ((HALF - x0, c), (-HALF - x0, c), (HALF - y0, s), (-HALF - y0, s)):
        if abs(d) > 1e-12 and wall / d > 0:
            best = min(best, wall / d)
    return best


def write_bag(path):
    beams = 360
    with rosbag.Bag(path, "w") as bag:
        for i in range(SCANS):
            scan = LaserScan()
            scan.header.stamp = rospy.Time.from_sec(100.0 + PERIOD * i)
            scan.header.frame_id = "/laser"
            scan.angle_min = -math.pi
            scan.angle_increment = 2 * math.pi / beams
            scan.angle_max = scan.angle_min + (beams - 1) * scan.angle_increment
            scan.range_min, scan.range_max = 0.05, 20.0
            # A deterministic 5 mm ripple stands in for the range noise.
            scan.ranges = [room_range(scan.angle_min + k * scan.angle_increment) + 0.005 * math.sin(7.0 * k + i)
                           for k in range(beams)]
            bag.write("/scan", scan, scan.header.stamp)


class CheckScanOnlyBag(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.bag = os.path.join(tempfile.mkdtemp(prefix="scan_only_bag_"), "scan_only.bag")
        write_bag(cls.bag)
        # The bag at rate 1 plus the nodelets' start-up, with a wide margin for a loaded machine.
        cls.limit = lt.work_limit(SCANS * PERIOD, 1.0)

    def replay(self, name, args):
        """replay.launch with `args` on the test's master; returns (final line_map, its map_quality)."""
        maps = lt.Collector("line_map", LineMap)
        qualities = lt.Collector("map_quality", MapQuality)
        log = open(os.path.join(lt.artifact_dir(), "scan_only_bag_%s.log" % name), "w")
        proc = subprocess.Popen(["roslaunch", os.path.join(lt.repo_root(), "launch", "replay.launch"),
                                 "bag:=" + self.bag, "rate:=1", "output:=screen"] + args,
                                stdout=log, stderr=subprocess.STDOUT, start_new_session=True,
                                # Unbuffered: roslaunch's own lines ("process has finished") reach the log as
                                # they happen, not when its buffer fills or it exits.
                                env=dict(os.environ, PYTHONUNBUFFERED="1"))
        try:
            lt.wait_until(lambda: maps.messages, "a line_map (%s)" % " ".join(args),
                          lambda: "none; see %s" % log.name, self.limit, gone=lambda: (
                              "roslaunch exited (%s)" % proc.returncode if proc.poll() is not None else None))
            line_map = maps.messages[-1][1]
            quality = lt.wait_for_quality_of(qualities, line_map, "the map_quality of the line_map (%s)"
                                             % " ".join(args), self.limit)
            # Everything the map will get: the player played the whole bag.
            lt.wait_until(lambda: "player-" in open(log.name).read() and "process has finished" in open(
                log.name).read(), "rosbag play to finish", lambda: "still playing", self.limit)
            line_map = maps.messages[-1][1]
        finally:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(60)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            log.close()
            for c in (maps, qualities):
                c.sub.unregister()
        return line_map, quality

    def check_room(self, line_map, quality, frame):
        self.assertEqual(line_map.header.frame_id.lstrip("/"), frame)
        self.assertGreaterEqual(len(line_map.segments), 4, "a square room has four walls")
        self.assertGreater(line_map.keyframes, 0)
        self.assertGreater(quality.quality, 50.0, "the map must fit the scans it was built from")

    def test_map_frame_is_the_laser_frame(self):
        line_map, quality = self.replay("map_frame", ["map_frame:=/laser"])
        print("map_frame:=/laser: %d map segments, %d keyframes, quality %.1f %%"
              % (len(line_map.segments), line_map.keyframes, quality.quality))
        self.check_room(line_map, quality, "laser")

    def test_static_scan_tf(self):
        line_map, quality = self.replay("static_scan_tf", ["static_scan_tf:=true", "scan_frame:=/laser"])
        print("static_scan_tf:=true scan_frame:=/laser: %d map segments, %d keyframes, quality %.1f %%"
              % (len(line_map.segments), line_map.keyframes, quality.quality))
        self.check_room(line_map, quality, "map")
        self.assertEqual(line_map.keyframes, 1, "the robot is taken as standing still: one keyframe")


if __name__ == "__main__":
    rospy.init_node("check_scan_only_bag")
    rostest.rosrun("line_map_eval", "check_scan_only_bag", CheckScanOnlyBag)

#!/usr/bin/python3
"""rostest (play_bag.test): simulates a small office bag with simulate_world, plays it with
`rosbag play --clock` and checks what arrives: every scan with its frame and beam count, the
tf tree (odom->base_link per scan, map->odom, static base_link->laser) and one
optimized_trajectory at the end holding one true pose per keyframe (= per scan)."""

import math
import os
import shutil
import subprocess
import tempfile
import threading
import time
import unittest

import rospkg
import rospy
import rostest
import yaml
from nav_msgs.msg import Path
from sensor_msgs.msg import LaserScan
from tf2_msgs.msg import TFMessage

SCANS = 60


class PlayBag(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("check_topics")
        cls.lock = threading.Lock()
        cls.scans, cls.paths, cls.tf, cls.tf_static = [], [], [], []
        cls.tmp = tempfile.mkdtemp(prefix="play_bag_")
        default_world = os.path.join(
            rospkg.RosPack().get_path("line_map_eval"), "..", "config", "worlds", "office.yaml")
        world = rospy.get_param("~world", default_world)
        cls.bag = os.path.join(cls.tmp, "office.bag")
        cls.sim = subprocess.run(
            ["rosrun", "line_map_eval", "simulate_world", world, cls.bag, "--scans", str(SCANS), "--no-progress"],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=120)
        if cls.sim.returncode != 0:
            return
        with open(os.path.join(cls.tmp, "office.truth.yaml")) as f:
            cls.truth = yaml.safe_load(f)

        def keep(store):
            def callback(msg):
                with cls.lock:
                    store.append(msg)
            return callback

        subs = [rospy.Subscriber("scan", LaserScan, keep(cls.scans), queue_size=1000),
                rospy.Subscriber("optimized_trajectory", Path, keep(cls.paths), queue_size=10),
                rospy.Subscriber("tf", TFMessage, keep(cls.tf), queue_size=1000),
                rospy.Subscriber("tf_static", TFMessage, keep(cls.tf_static), queue_size=10)]
        # The bag spans one lap (~200 s of stamps); played 50 times faster. The player waits
        # until every topic of the bag has a subscriber, so nothing is lost at the start.
        cls.play = subprocess.run(
            ["rosbag", "play", "--clock", "--quiet", "--wait-for-subscribers", "--rate=50", cls.bag],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=120)
        # Until every scan and the trajectory arrived (the event), at most 60 s of wall time.
        deadline = time.time() + 60.0
        while time.time() < deadline and (len(cls.scans) < SCANS or not cls.paths):
            time.sleep(0.1)
        time.sleep(0.5)  # anything late would show up as an extra message
        for s in subs:
            s.unregister()

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def setUp(self):
        self.assertEqual(self.sim.returncode, 0, "simulate_world failed:\n" + self.sim.stdout)

    def test_player_succeeded(self):
        # rosbag play reports some failures (e.g. a connection without md5sum) only as FATAL.
        self.assertEqual(self.play.returncode, 0, "rosbag play failed:\n" + self.play.stdout)
        self.assertNotIn("FATAL", self.play.stdout)
        self.assertNotIn("ERROR", self.play.stdout)

    def test_scans(self):
        self.assertEqual(len(self.scans), SCANS)
        laser = self.truth["laser"]
        stamps = [s.header.stamp.to_sec() for s in self.scans]
        self.assertEqual(stamps, sorted(stamps))
        for s in self.scans:
            self.assertEqual(s.header.frame_id, "laser")
            self.assertEqual(len(s.ranges), laser["beams"])
            self.assertAlmostEqual(s.angle_min, laser["angle_min"], places=5)
            self.assertAlmostEqual(s.angle_increment, laser["angle_increment"], places=6)
            self.assertAlmostEqual(s.range_max, laser["range_max"], places=5)
        # The scan stamps are the ground truth's, in order.
        for s, t in zip(self.scans, self.truth["scans"]):
            self.assertAlmostEqual(s.header.stamp.to_sec(), t["stamp"], places=6)

    def test_trajectory_once_with_every_keyframe(self):
        self.assertEqual(len(self.paths), 1, "expected one trajectory, at the loop closure")
        path = self.paths[0]
        self.assertEqual(path.header.frame_id, "map")
        self.assertEqual(len(path.poses), SCANS)
        self.assertAlmostEqual(path.header.stamp.to_sec(), self.truth["scans"][-1]["stamp"], places=6)
        # Each pose is the true base pose: the truth's laser pose minus the mounting offset.
        bx, by, bth = self.truth["base_to_laser"]
        for p, t in zip(path.poses, self.truth["scans"]):
            x, y, th = t["pose"]
            base_x = x - (math.cos(th - bth) * bx - math.sin(th - bth) * by)
            base_y = y - (math.sin(th - bth) * bx + math.cos(th - bth) * by)
            self.assertAlmostEqual(p.pose.position.x, base_x, places=5)
            self.assertAlmostEqual(p.pose.position.y, base_y, places=5)
            self.assertAlmostEqual(p.header.stamp.to_sec(), t["stamp"], places=6)

    def test_tf_tree(self):
        pairs = {}
        for msg in self.tf:
            for t in msg.transforms:
                pairs[(t.header.frame_id, t.child_frame_id)] = pairs.get((t.header.frame_id, t.child_frame_id), 0) + 1
        self.assertEqual(pairs.get(("odom", "base_link")), SCANS, pairs)
        self.assertIn(("map", "odom"), pairs)
        static = {(t.header.frame_id, t.child_frame_id): t for msg in self.tf_static for t in msg.transforms}
        self.assertIn(("base_link", "laser"), static)
        mount = static[("base_link", "laser")].transform.translation
        self.assertAlmostEqual(mount.x, self.truth["base_to_laser"][0], places=6)
        self.assertAlmostEqual(mount.y, self.truth["base_to_laser"][1], places=6)


if __name__ == "__main__":
    rostest.rosrun("line_map_eval", "play_bag", PlayBag)

#!/usr/bin/python3
"""Rostest checker (test/localization.test): the localization nodelet in linemap.launch localize:=true.

1. The nodelet starts before its map file exists: it must say so in its diagnostics and load the file
   once it appears (the map of our SLAM on the whole Intel raw log, from linemap_batch).
2. From an initial pose on `initialpose` (the SLAM's frame starts at the first scan's pose), the first
   part of a 1500-scan prefix of the log (scan + odometry tf) is played: every scan must be localized,
   its pose stamped with the scan's stamp, equal within 5 cm to what linemap_relations --localize (the
   same core, offline, on the same log) gives for that scan.
3. `global_localization` is called and the rest is played: the pose must be found again (a recovery in
   the diagnostics) and end within 0.3 m and 5 degrees of the offline pose.
Over both parts, the relations of the log (Kuemmerle et al.) between published poses must be met to
0.05 m on average. That bound does not tell a localizer from dead reckoning: on this prefix the raw
odometry meets the relations to 0.0167 m. What does is the offline run on the whole log (the same core):
its trajectory must meet the relations to WHOLE_LOG_FLOOR, where a localizer that only dead-reckons from
the initial pose (a constant transform of the raw odometry) scores 7.37 m."""
import math
import os
import struct
import sys
import tempfile
import unittest

import rospy
import rostest
import tf2_ros
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseWithCovarianceStamped
from std_srvs.srv import Empty

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402

SCANS = 1500
FIRST_PART_SECONDS = 150.0  # of log time: about half of the prefix
RATE = 20
# During global localization a search over the map holds the nodelet's queue for a while: the second
# part plays slower, so that the scans queued behind a search stay within the subscription's queue.
SEARCH_RATE = 4
# [m] the offline localizer's relations error on the whole Intel log (every relation). Measured
# 2026-11-27 on 4f9fdb2 with linemap_relations: localized in the SLAM's map 0.0154 m; raw odometry, i.e. a
# localizer that dead-reckons (also measured as --localize-param scan/min_points=100000: no scan matched)
# 7.37 m. Twice the localizer's figure: far from what dead reckoning or a localizer losing the track
# for a stretch scores.
WHOLE_LOG_FLOOR = 0.03
key = lt.stamp_key
relations_error = lt.relations_error


def check_whole_log(trajectory_file, relations):
    """The failure message when the trajectory (linemap_relations --write) misses the floor, else None."""
    mean, count = relations_error(lt.read_trajectory(trajectory_file), relations)
    if count != len(relations):
        return "%d of %d relations have both poses" % (count, len(relations))
    if not mean < WHOLE_LOG_FLOOR:
        return "relations error %.4f m on the whole log, floor %.3f m" % (mean, WHOLE_LOG_FLOOR)
    return None


class CheckLocalization(unittest.TestCase):
    def test_localization_in_a_saved_map(self):
        data = lt.datasets_dir()
        raw, rel = os.path.join(data, "intel.clf.bz2"), os.path.join(data, "intel.relations")
        if not os.path.exists(raw):
            self.skipTest("Intel dataset missing under " + data)
        map_file = rospy.get_param("/localization/map_file")
        self.assertFalse(os.path.exists(map_file))

        diag = {}

        def on_diag(msg):
            for s in msg.status:
                if s.name.endswith("line map localization"):
                    diag.update({kv.key: kv.value for kv in s.values})
                    diag["summary"] = s.message

        rospy.Subscriber("/diagnostics", DiagnosticArray, on_diag, queue_size=50)
        poses = {}
        rospy.Subscriber("/localization_pose", PoseWithCovarianceStamped, lambda m: poses.__setitem__(
            m.header.stamp.to_sec(), (m.pose.pose.position.x, m.pose.pose.position.y,
                                      2.0 * math.atan2(m.pose.pose.orientation.z, m.pose.pose.orientation.w),
                                      m.header.frame_id)), queue_size=2000)
        buf = tf2_ros.Buffer(rospy.Duration(600))
        tf2_ros.TransformListener(buf)
        lt.wait_until(lambda: "no map" in diag.get("summary", ""), "the nodelet to report its missing map",
                      lambda: diag.get("summary"), 60.0)

        # The map, the bag and the offline reference.
        work = tempfile.mkdtemp(prefix="localization_")
        session = os.path.join(work, "intel.session")
        rc, log = lt.run(["rosrun", "line_map_eval", "linemap_batch", raw, "--slam", "--merger", "cae",
                          "--no-figures", "--no-progress", "--out", work, "--save-session", session], 900)
        self.assertEqual(rc, 0, log)
        # The session holds the SLAM's keyframes (as many as its graph's nodes) and the cae map file's
        # text unchanged.
        records = dict(lt.session_records(session))
        keyframes = struct.unpack_from("<Q", records["KEYF"])[0]
        self.assertEqual(keyframes, struct.unpack_from("<Q", records["NODE"])[0])
        self.assertIn("wrote the session %s: %d keyframes" % (session, keyframes), log)
        with open(os.path.join(work, "cae", "map.yaml"), "rb") as f:
            self.assertEqual(records["LMAP"], f.read())
        bag = os.path.join(work, "intel.bag")
        rc, log = lt.run(["rosrun", "line_map_eval", "carmen_to_bag", raw, bag, "--max-scans", str(SCANS)], 300)
        self.assertEqual(rc, 0, log)
        reference_file = os.path.join(work, "offline.txt")
        rc, log = lt.run(["rosrun", "line_map_eval", "linemap_relations", raw, rel, "--localize",
                          os.path.join(work, "cae", "map.yaml"), "--initial-pose", "0,0,0", "--write",
                          reference_file], 900)
        self.assertEqual(rc, 0, log)
        print(log)
        relations = lt.read_relations(rel)
        failure = check_whole_log(reference_file, relations)
        self.assertIsNone(failure, failure)
        with open(reference_file) as f:
            offline = [tuple(float(v) for v in line.split()) for line in f][:SCANS]
        # The bag's scans are the log's first SCANS, in order; poses are keyed by the bag's stamps, and
        # the log's stamps (those of the offline run and of the relations) are matched by index.
        import rosbag
        with rosbag.Bag(bag) as b:
            stamps = [m.header.stamp.to_sec() for _, m, _ in b.read_messages(topics=["/scan", "scan"])]
            odometry_end = max(t.header.stamp.to_sec() for _, m, _ in b.read_messages(topics=["/tf", "tf"])
                               for t in m.transforms if t.child_frame_id.lstrip("/") == "base_link")
        self.assertEqual(len(stamps), SCANS)
        # A scan after the last odometry reading waits for it as long as the bag is stopped.
        placeable = [t for t in stamps if t <= odometry_end]
        reference = {t: r[1:] for t, r in zip(stamps, offline)}
        log_stamp = {t: key(r[0]) for t, r in zip(stamps, offline)}

        # The map appears: the nodelet loads it on its own (it retries a missing file).
        os.makedirs(os.path.dirname(map_file), exist_ok=True)
        os.rename(os.path.join(work, "cae", "map.yaml"), map_file)
        lt.wait_until(lambda: diag.get("summary") in ("tracking", "global localization"), "the map to load",
                      lambda: diag.get("summary"), 60.0)

        initial = rospy.Publisher("/initialpose", PoseWithCovarianceStamped, queue_size=1, latch=True)
        lt.wait_until(lambda: initial.get_num_connections() > 0, "the nodelet's initialpose subscription",
                      lambda: "no subscriber", 30.0)
        msg = PoseWithCovarianceStamped()
        msg.header.frame_id = "map"
        msg.pose.pose.orientation.w = 1.0
        initial.publish(msg)
        lt.wait_until(lambda: diag.get("summary") == "tracking", "the initial pose to be taken",
                      lambda: diag.get("summary"), 60.0)

        first = [t for t in stamps if t < stamps[0] + FIRST_PART_SECONDS]
        self.play(bag, ["--duration", str(FIRST_PART_SECONDS)])
        lt.wait_until(lambda: int(diag.get("scans", "0")) >= len(first), "the first part's %d scans" % len(first),
                      lambda: str(diag), lt.work_limit(FIRST_PART_SECONDS, RATE))
        lt.wait_until(lambda: all(t in poses for t in first), "a pose for every scan of the first part",
                      lambda: "%d poses" % len(poses), 60.0)
        worst = max(math.hypot(poses[t][0] - reference[t][0], poses[t][1] - reference[t][1]) for t in first)
        self.assertLess(worst, 0.05, "the nodelet's poses differ from the offline run's by up to %.3f m" % worst)
        self.assertTrue(all(poses[t][3] == "map" for t in first))

        recovered = int(diag.get("recovered", "0"))
        rospy.ServiceProxy("/global_localization", Empty)()
        lt.wait_until(lambda: diag.get("summary") == "global localization", "global localization to start",
                      lambda: diag.get("summary"), 60.0)
        self.play(bag, ["--start", str(FIRST_PART_SECONDS)], SEARCH_RATE)
        lt.wait_until(lambda: int(diag.get("scans", "0")) >= len(placeable), "all %d scans up to the last "
                      "odometry" % len(placeable), lambda: str(diag), lt.work_limit(stamps[-1] - stamps[0], SEARCH_RATE))
        self.assertGreater(int(diag.get("recovered", "0")), recovered, "no recovery after global_localization")
        self.assertEqual(diag.get("summary"), "tracking")
        last = placeable[-1]
        lt.wait_until(lambda: last in poses, "the pose of the last scan", lambda: "%d poses" % len(poses), 60.0)
        off = math.hypot(poses[last][0] - reference[last][0], poses[last][1] - reference[last][1])
        turn = abs(math.atan2(math.sin(poses[last][2] - reference[last][2]), math.cos(poses[last][2] - reference[last][2])))
        self.assertLess(off, 0.3)
        self.assertLess(turn, math.radians(5.0))
        self.assertTrue(buf.can_transform("map", "odom", rospy.Time.from_sec(last), rospy.Duration(10.0)))

        mean, count = relations_error({log_stamp[t]: p[:3] for t, p in poses.items() if t in log_stamp}, relations)
        summary = ("localization: %d of %d scans posed; first part within %.3f m of the offline run; after "
                   "global localization %.3f m, %.1f deg off at the last scan; relations error %.4f m over %d "
                   "relations" % (len(poses), SCANS, worst, off, math.degrees(turn), mean, count))
        print(summary)
        with open(os.path.join(lt.artifact_dir(), "localization.txt"), "w") as f:
            f.write(summary + "\n")
        self.assertGreater(count, 50)
        self.assertLess(mean, 0.05)

    def play(self, bag, extra, rate=RATE):
        cmd = ["rosbag", "play", "--clock", "--quiet", "--rate", str(rate), "--wait-for-subscribers"] + extra + [bag]
        rc, out = lt.run(cmd, lt.work_limit(300.0, rate))
        self.assertEqual(rc, 0, out)


if __name__ == "__main__":
    rospy.init_node("check_localization")
    rostest.rosrun("line_map_eval", "check_localization", CheckLocalization)

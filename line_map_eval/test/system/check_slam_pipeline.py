#!/usr/bin/python3
"""Rostest checker (test/slam_pipeline.test, test/slam_pipeline_clinic.test): the first scans of a raw
CARMEN log (private parameters ~dataset, default the Intel log, ~scans, default 1500, ~rate, default 20),
converted without the corrected trajectory, played through linemap.launch slam:=true. Waits until the
SLAM has handled every scan of the bag (its diagnostics), then checks the trajectories it published
(poses stamped with scan stamps, one per keyframe, finite), tf map -> odom at the last scan, and that
the merger adjusted its map to them and holds map segments."""
import math
import os
import struct
import sys
import tempfile
import unittest

import rospy
import rostest
import tf2_ros
from line_map_msgs.srv import LoadSession, LoadSessionRequest, SaveMap
from nav_msgs.msg import Path

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402



class CheckSlamPipeline(unittest.TestCase):
    def test_slam_feeds_the_merger(self):
        dataset = rospy.get_param("~dataset", "intel.clf.bz2")
        SCANS = int(rospy.get_param("~scans", 1500))
        RATE = float(rospy.get_param("~rate", 20))
        raw = os.path.join(lt.datasets_dir(), dataset)
        if not os.path.exists(raw):
            self.skipTest("dataset missing: " + raw)
        bag = os.path.join(tempfile.mkdtemp(prefix="slam_pipeline_"), dataset.split(".")[0] + ".bag")
        rc, log = lt.run(["rosrun", "line_map_eval", "carmen_to_bag", raw, bag, "--max-scans", str(SCANS)], 300)
        self.assertEqual(rc, 0, log)
        import rosbag
        with rosbag.Bag(bag) as b:
            stamps = sorted(m.header.stamp.to_sec() for _, m, _ in b.read_messages(topics=["/scan", "scan"]))
        self.assertEqual(len(stamps), SCANS)

        diagnostics = lt.component_diagnostics(slam="laser slam", merging="line map merging")
        slam, merging, paths = diagnostics["slam"], diagnostics["merging"], []
        rospy.Subscriber("/optimized_trajectory", Path, lambda m: paths.append(m), queue_size=100)
        buf = tf2_ros.Buffer(rospy.Duration(600))
        tf2_ros.TransformListener(buf)
        lt.wait_until(lambda: "scans" in slam and "keyframes" in merging, "the SLAM and merger diagnostics",
                      lambda: "slam %s, merging %s" % (bool(slam), bool(merging)), 60.0)

        lt.play(bag, RATE)
        # A bound only: the SLAM may take its scans at 2x real time on a loaded machine (about 1.9x measured
        # under stress-ng on both cores), however fast the bag plays.
        limit = lt.work_limit(stamps[-1] - stamps[0], 2)
        lt.wait_until(lambda: int(slam.get("scans", "0")) >= SCANS, "the SLAM to handle all %d scans" % SCANS,
                      lambda: "%s scans" % slam.get("scans"), limit, gone=lt.gone_nodes("/tf"))
        lt.wait_until(lambda: paths and int(merging.get("adjustments", "0")) >= 1,
                      "a trajectory and the merger's adjustment to it",
                      lambda: "%d paths, merger %s" % (len(paths), merging.get("adjustments")), 60.0)
        summary = ("slam: %s keyframes, %s closures accepted, %s rejected (score), %s poor matches; %d trajectories; "
              "merger: %s adjustments, %s map segments, %s keyframes (chosen by %s; %s node keyframes)" % (
                  slam.get("keyframes"), slam.get("loop closures accepted"), slam.get("loop closures rejected (score)"),
                  slam.get("poor matches"), len(paths), merging.get("adjustments"), merging.get("map segments"),
                  merging.get("keyframes"), merging.get("keyframes chosen by"), merging.get("node keyframes")))
        print(summary)
        with open(os.path.join(lt.artifact_dir(), "slam_pipeline.txt"), "w") as f:
            f.write(summary + "\n")
        self.assertEqual(int(slam["scans out of order (ignored)"]), 0)
        self.assertEqual(int(slam["scans dropped (no tf)"]), 0)
        self.assertGreater(int(slam["matched scans"]), SCANS // 4)
        self.assertGreater(int(merging["map segments"]), 0)

        last = paths[-1]
        self.assertEqual(last.header.frame_id, "map")
        self.assertGreater(len(last.poses), 10)
        previous = -1.0
        for p in last.poses:
            t = p.header.stamp.to_sec()
            self.assertGreater(t, previous, "keyframe poses in stamp order")
            previous = t
            # Every pose carries the stamp of one of the bag's scans (to the nanosecond of ROS time).
            near = min(abs(s - t) for s in stamps[max(0, bisect(stamps, t) - 1):bisect(stamps, t) + 1])
            self.assertLess(near, 1e-6, "pose stamp %.9f is no scan stamp" % t)
            self.assertTrue(all(math.isfinite(v) for v in (p.pose.position.x, p.pose.position.y,
                                                           p.pose.orientation.z, p.pose.orientation.w)))
        # tf map -> odom at the last scan: the SLAM's.
        self.assertTrue(buf.can_transform("map", "odom", rospy.Time.from_sec(stamps[-1]), rospy.Duration(5.0)))
        self.check_sessions(int(slam["keyframes"]), paths)

    def check_sessions(self, keyframes, paths):
        """~save_session writes the SLAM's graph with the merger's map (read here by an independent reader);
        a damaged copy is refused naming its record, the running SLAM kept; the good file loads back."""
        work = tempfile.mkdtemp(prefix="slam_session_")
        path = os.path.join(work, "run.session")
        rospy.wait_for_service("/slam/save_session", 30.0)
        save = rospy.ServiceProxy("/slam/save_session", SaveMap)
        proxy = rospy.ServiceProxy("/slam/load_session", LoadSession)
        load = lambda p: proxy(path=p, start=LoadSessionRequest.NEWEST_KEYFRAME)  # the bag is over: no scan to search

        answer = save(path)
        self.assertTrue(answer.success, answer.message)
        records = dict(lt.session_records(path))
        self.assertEqual(struct.unpack_from("<Q", records["KEYF"])[0], keyframes)
        self.assertIn(b"method: cae", records.get("LMAP", b""), "the merger's map in the session")
        with open(path, "rb") as f:
            data = bytearray(f.read())
        data[100] ^= 0xFF  # inside the keyframes' record
        damaged = os.path.join(work, "damaged.session")
        with open(damaged, "wb") as f:
            f.write(data)
        answer = proxy(path=path, start=7)
        self.assertFalse(answer.success)
        self.assertIn("start must be", answer.message)
        answer = load(damaged)
        self.assertFalse(answer.success)
        self.assertIn("record 'KEYF'", answer.message)
        published = len(paths)
        answer = load(path)
        self.assertTrue(answer.success, answer.message)
        self.assertIn("the line map to", answer.message)
        lt.wait_until(lambda: len(paths) > published, "the loaded session's trajectory", lambda: str(len(paths)), 30.0)
        self.assertEqual(len(paths[-1].poses), keyframes)


def bisect(values, x):
    import bisect as b
    return b.bisect_left(values, x)


if __name__ == "__main__":
    rospy.init_node("check_slam_pipeline")
    rostest.rosrun("line_map_eval", "check_slam_pipeline", CheckSlamPipeline)

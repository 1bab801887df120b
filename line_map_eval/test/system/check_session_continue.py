#!/usr/bin/python3
"""Rostest checker (test/session_continue.test): continuing a saved session live from an unknown start
(linemap.launch slam:=true session:=F). The first 1500 scans of the Intel raw log are mapped offline
(linemap_batch --slam --merger cae --save-session F); the pipeline is started with session:=F, and the
next 1200 scans, converted to a bag of their own, are played. The SLAM must find the robot in the saved map
(its diagnostics), then publish trajectories that hold every saved keyframe (by stamp, moved by the joined
graph only a little) and new keyframes after them, with closures between the two; the merger must have the
saved map (loaded through its load_map when the robot was found) and adjust it to the joined trajectories."""
import bz2
import math
import os
import re
import sys
import tempfile
import unittest

import rospy
import rostest
from nav_msgs.msg import Path

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402

FIRST, SECOND = 1500, 1200
RATE = 2


def split_log(raw, out_dir):
    """The raw log as two logs: its first FIRST scans and the SECOND after them (header lines in both)."""
    head, parts, scans = [], ([], []), 0
    with bz2.open(raw, "rt") as f:
        for line in f:
            kind = line.split(" ", 1)[0]
            if kind in ("#", "PARAM"):
                head.append(line)
                continue
            part = 0 if scans < FIRST else 1
            if kind == "FLASER":
                scans += 1
                if scans > FIRST + SECOND:
                    break
            parts[part].append(line)
    paths = [os.path.join(out_dir, name) for name in ("first.clf", "second.clf")]
    for path, lines in zip(paths, parts):
        with open(path, "w") as f:
            f.writelines(head + lines)
    return paths


class CheckSessionContinue(unittest.TestCase):
    def test_a_saved_session_goes_on_live(self):
        raw = os.path.join(lt.datasets_dir(), "intel.clf.bz2")
        if not os.path.exists(raw):
            self.skipTest("dataset missing: " + raw)
        work = tempfile.mkdtemp(prefix="session_continue_")
        first, second = split_log(raw, work)
        session = os.path.join(work, "first.session")
        rc, log = lt.run(["rosrun", "line_map_eval", "linemap_batch", first, "--slam", "--merger", "cae",
                          "--no-figures", "--no-progress", "--out", os.path.join(work, "batch"),
                          "--save-session", session], 600)
        self.assertEqual(rc, 0, log)
        saved, saved_map_keyframes = lt.session_keyframes(session)
        bag = os.path.join(work, "second.bag")
        rc, log = lt.run(["rosrun", "line_map_eval", "carmen_to_bag", second, bag, "--no-progress"], 300)
        self.assertEqual(rc, 0, log)
        _, _, bag_seconds = lt.bag_scans(bag)

        paths = []
        rospy.Subscriber("/optimized_trajectory", Path, lambda m: paths.append(m), queue_size=100)
        pipeline, slam, merging, key = lt.start_session_pipeline("session_continue", session)
        try:
            # Played at twice the log's speed: the scans searched wait for the global search, and the merger
            # drops those the SLAM has not posed within its tf_timeout once it is found (until it caught up).
            lt.play(bag, RATE)
            limit = lt.work_limit(bag_seconds, RATE)

            def found_at():
                m = re.search(r"found at scan (\d+)", slam.get(key, ""))
                return int(m.group(1)) if m else None

            # The scans before the robot was found only search; every later one goes to the SLAM; the merger
            # merges new keyframes into the saved map (how many of the scans it had to drop is not asserted).
            lt.wait_until(lambda: found_at() is not None and int(slam.get("scans", "0")) + found_at() >= SECOND
                          and paths and len(paths[-1].poses) > len(saved) + 20
                          and int(merging.get("adjustments", "0")) >= 1
                          and int(merging.get("keyframes", "0")) > saved_map_keyframes,
                          "the continued session's trajectory and the merger's adjustment to it",
                          lambda: "%s; SLAM %s scans; %d paths (%d poses, %d saved); merger %s keyframes (%d saved), "
                          "%s adjustments" % (slam.get(key), slam.get("scans"), len(paths),
                                              len(paths[-1].poses) if paths else 0, len(saved),
                                              merging.get("keyframes"), saved_map_keyframes,
                                              merging.get("adjustments")),
                          limit, gone=lt.gone_nodes("/tf"))
        finally:
            lt.stop(pipeline, 30)
        found = found_at()
        last = paths[-1].poses
        moved = max(math.hypot(p.pose.position.x - x, p.pose.position.y - y)
                    for p, (_, x, y) in zip(last, saved))
        summary = ("session continued: found at scan %d of the second run; %d saved keyframes (moved at most %.3f m "
                   "by the joined graph), %d new; merger %s keyframes (%d saved), %s adjustments" % (
                       found, len(saved), moved, len(last) - len(saved), merging.get("keyframes"),
                       saved_map_keyframes, merging.get("adjustments")))
        print(summary)
        with open(os.path.join(lt.artifact_dir(), "session_continue.txt"), "w") as f:
            f.write(summary + "\n")
        self.assertLessEqual(found, 400)
        for p, (t, _, _) in zip(last, saved):
            self.assertAlmostEqual(p.header.stamp.to_sec(), t, delta=1e-6, msg="a saved keyframe's stamp")
        self.assertLess(moved, 0.5, "the joined graph moved a saved keyframe by more than its own error")
        self.assertGreater(last[len(saved)].header.stamp.to_sec(), saved[-1][0], "new keyframes follow the saved")
        self.assertGreaterEqual(int(slam["loop closures accepted"]), 5)


if __name__ == "__main__":
    rospy.init_node("check_session_continue")
    rostest.rosrun("line_map_eval", "check_session_continue", CheckSessionContinue)

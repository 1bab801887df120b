#!/usr/bin/python3
"""Rostest checker (test/session_continue.test): continuing a saved session live from an unknown start
(linemap.launch slam:=true, then the SLAM's ~load_session F with start SEARCH). The first 1500 scans of the Intel raw log are mapped offline
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
from line_map_msgs.srv import SaveMap
from nav_msgs.msg import Path

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402

FIRST, SECOND = 1500, 1200
RATE = 2
# The join variant (test/session_join.test): the search gives up long before the robot is found (scan 288 at
# full search), at the log's own speed: mapping apart and searching share the SLAM's thread.
JOIN_SEARCH, JOIN_RATE = 20, 1


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


def rigid_residual(pairs):
    """The largest distance left after the least-squares rigid fit of the first points onto the second."""
    n = float(len(pairs))
    ax, ay = sum(p[0][0] for p in pairs) / n, sum(p[0][1] for p in pairs) / n
    bx, by = sum(p[1][0] for p in pairs) / n, sum(p[1][1] for p in pairs) / n
    cross = sum((a[0] - ax) * (b[1] - by) - (a[1] - ay) * (b[0] - bx) for a, b in pairs)
    dot = sum((a[0] - ax) * (b[0] - bx) + (a[1] - ay) * (b[1] - by) for a, b in pairs)
    t = math.atan2(cross, dot)
    c, s = math.cos(t), math.sin(t)
    return max(math.hypot(c * (a[0] - ax) - s * (a[1] - ay) + bx - b[0], s * (a[0] - ax) + c * (a[1] - ay) + by - b[1])
               for a, b in pairs)


class CheckSessionContinue(unittest.TestCase):
    def prepare(self, name):
        """The saved session of the first part and the second part as a bag: (session, saved keyframes, the saved
        map's keyframes, bag, its seconds)."""
        raw = os.path.join(lt.datasets_dir(), "intel.clf.bz2")
        if not os.path.exists(raw):
            self.skipTest("dataset missing: " + raw)
        work = tempfile.mkdtemp(prefix=name + "_")
        first, second = split_log(raw, work)
        session = os.path.join(work, "first.session")
        saved, saved_map_keyframes = lt.save_batch_session(self, first, work, session)
        bag = os.path.join(work, "second.bag")
        rc, log = lt.run(["rosrun", "line_map_eval", "carmen_to_bag", second, bag, "--no-progress"], 300)
        self.assertEqual(rc, 0, log)
        _, _, bag_seconds = lt.bag_scans(bag)
        return session, saved, saved_map_keyframes, bag, bag_seconds

    def test_a_saved_session_goes_on_live(self):
        if rospy.get_param("~join", False):
            self.join_later()
            return
        session, saved, saved_map_keyframes, bag, bag_seconds = self.prepare("session_continue")
        paths = []
        rospy.Subscriber("/optimized_trajectory", Path, lambda m: paths.append(m), queue_size=100)
        # The session given through ~load_session (SEARCH) on a running pipeline: session_join.test and
        # changed_world.test give theirs as ~session.
        pipeline, slam, merging, key = lt.start_session_pipeline("session_continue", session, by_service=True)
        try:
            # Played at twice the log's speed: the scans searched wait for the global search; the merger waits
            # for the SLAM to pose each later one however long that takes (lt.SESSION_TF_TIMEOUT).
            lt.play(bag, RATE)
            limit = lt.work_limit(bag_seconds, RATE)

            def found_at():
                m = re.search(r"found at scan (\d+)", slam.get(key, ""))
                return int(m.group(1)) if m else None

            # The scans before the robot was found only search; every later one goes to the SLAM; the merger
            # merges new keyframes into the saved map.
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

    def join_later(self):
        """The search given up after JOIN_SEARCH scans (the robot is found later than that): the SLAM maps apart in
        its own frame, goes on looking, and joins the saved graph when found; the merger merges the saved line map
        into its own at the place found (append_map)."""
        session, saved, saved_map_keyframes, bag, bag_seconds = self.prepare("session_join")
        paths = []
        rospy.Subscriber("/optimized_trajectory", Path, lambda m: paths.append(m), queue_size=100)
        pipeline, slam, merging, key = lt.start_session_pipeline("session_join", session, JOIN_SEARCH)
        try:
            lt.play(bag, JOIN_RATE)
            limit = lt.work_limit(bag_seconds, JOIN_RATE)
            lt.wait_until(lambda: "joined the saved session" in slam.get(key, "")
                          and paths and len(paths[-1].poses) > len(saved) + 20
                          and int(merging.get("keyframes", "0")) > saved_map_keyframes + 20,
                          "the joined trajectory and the saved line map in the merger's",
                          lambda: "%s; %d paths (%d poses, %d saved); merger %s keyframes (%d saved)" % (
                              slam.get(key), len(paths), len(paths[-1].poses) if paths else 0, len(saved),
                              merging.get("keyframes"), saved_map_keyframes),
                          limit, gone=lt.gone_nodes("/tf"))
            # The joined line map as an artefact (linemap_export draws it).
            rospy.wait_for_service("/line_map_merging/save_map", timeout=60.0)
            saved_map = rospy.ServiceProxy("/line_map_merging/save_map", SaveMap)(
                path=os.path.join(lt.artifact_dir(), "session_join_map.yaml"))
            self.assertTrue(saved_map.success, saved_map.message)
        finally:
            lt.stop(pipeline, 30)
        last = paths[-1].poses
        pairs = [((p.pose.position.x, p.pose.position.y), (x, y)) for p, (_, x, y) in zip(last, saved)]
        residual = rigid_residual(pairs)
        summary = "session joined: %s; %d saved keyframes (%.3f m from their saved shape), %d new; merger %s " \
                  "keyframes (%d saved)" % (slam.get(key), len(saved), residual, len(last) - len(saved),
                                            merging.get("keyframes"), saved_map_keyframes)
        print(summary)
        with open(os.path.join(lt.artifact_dir(), "session_join.txt"), "w") as f:
            f.write(summary + "\n")
        for p, (t, _, _) in zip(last, saved):
            self.assertAlmostEqual(p.header.stamp.to_sec(), t, delta=1e-6, msg="a saved keyframe's stamp")
        # In this run's frame, the saved keyframes keep their shape: one rigid motion from where they were saved.
        self.assertLess(residual, 0.5, "the joined graph bent the saved keyframes")
        self.assertGreater(last[len(saved)].header.stamp.to_sec(), saved[-1][0], "this run's keyframes follow")


if __name__ == "__main__":
    rospy.init_node("check_session_continue")
    rostest.rosrun("line_map_eval", "check_session_continue", CheckSessionContinue)

#!/usr/bin/python3
"""Rostest checker (test/parity_loop.test, test/parity_intel.test): the nodelets (linemap.launch),
`linemap_batch BAG --replay` (the same OnlineMapper and OnlineEvaluator, fed in bag order) and
`linemap_batch BAG` by default (its online mergers driven through the same OnlineMapper, online_drive.hpp)
make the same map of the same bag with periodic loop-closure trajectories: the same keyframes (stamps),
the same map (segment count and ids equal, every endpoint within 1 mm) and, between the nodelets and
the replay (the same evaluator), quality within 0.1 point.

The checker plays the bag itself, message by message in bag order (/clock, /tf, /scan), so the order
the nodelets see is the bag's: before it publishes a trajectory it waits until the merger and the
evaluator have finished with every scan before it (their diagnostics count what they handled), and
after it until both have taken the trajectory. (The cores also make a node wait for a scan that
comes after its trajectory, node_keyframes.hpp; the wait keeps the adjustments in bag order too.)
The map of the nodelets is saved with ~save_map, whose keyframes give their stamps. Every wait ends
on its event; the limits are derived from the bag (linemap_testing.work_limit) and name what was
awaited and what arrived. Parameter ~dataset: loop | intel."""
import json
import os
import sys
import tempfile
import time
import unittest

import rosbag
import rospy
import rostest
import yaml
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan
from nav_msgs.msg import Path
from tf2_msgs.msg import TFMessage

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402

MERGING, EVALUATOR = "line map merging", "evaluator"


def make_bag(dataset, band):
    if dataset == "loop":
        bag, _, _ = lt.simulate("loop", band["seed"], band["scans"], "parity_loop_",
                                ["--every", str(band["every"])])
        return bag
    raw = os.path.join(lt.datasets_dir(), "intel.clf.bz2")
    corrected = os.path.join(lt.datasets_dir(), "intel-corrected.log.gz")
    if not (os.path.exists(raw) and os.path.exists(corrected)):
        raise unittest.SkipTest("Intel dataset missing under " + lt.datasets_dir())
    bag = os.path.join(tempfile.mkdtemp(prefix="parity_intel_"), "intel.bag")
    rc, log = lt.run(["rosrun", "line_map_eval", "carmen_to_bag", raw, bag, "--corrected", corrected,
                      "--every", str(band["every"]), "--max-scans", str(band["max_scans"])], 600)
    if rc != 0:
        raise RuntimeError("carmen_to_bag failed:\n" + log)
    return bag


class Driver:
    """Publishes a bag's messages in bag order and waits on the nodelets' diagnostics."""

    def __init__(self, bag, limit):
        from line_map_msgs.msg import LineMap, LineSegmentArray, MapQuality
        self.bag, self.limit = bag, limit
        self.diag = lt.Diagnostics()
        self.segments = lt.Collector("line_segments", LineSegmentArray)
        self.maps = lt.Collector("line_map", LineMap)
        self.qualities = lt.Collector("map_quality", MapQuality)
        self.clock = rospy.Publisher("/clock", Clock, queue_size=100)
        self.tf = rospy.Publisher("/tf", TFMessage, queue_size=1000)
        self.tf_static = rospy.Publisher("/tf_static", TFMessage, queue_size=10, latch=True)
        self.scan = rospy.Publisher("/scan", LaserScan, queue_size=1000)
        self.trajectory = rospy.Publisher("optimized_trajectory", Path, queue_size=10, latch=True)
        self.scans = self.trajectories = 0
        self.stamps = []  # of the scans published

    def handled(self):
        """(segment sets the merger handled, scans and segment sets the evaluator took)."""
        return (self.diag.counter(MERGING, "segment sets handled"),
                self.diag.counter(EVALUATOR, "scans") + self.diag.counter(EVALUATOR, "dropped scans (tf)"),
                self.diag.counter(EVALUATOR, "segment sets"))

    def wait_fresh(self, predicate, awaited):
        """Waits for diagnostics of both nodelets sent after now that satisfy `predicate`. No transform
        is re-sent meanwhile: every scan published has its transform, and a message that tf can place
        must come through (tf2_ros::MessageFilter once held one for ever; linemap's TfWaitQueue)."""
        since = dict(self.diag.received)
        lt.wait_until(lambda: all(self.diag.received.get(t, 0) > since.get(t, 0) for t in (MERGING, EVALUATOR))
                      and predicate(), awaited,
                      lambda: "merger handled %d, evaluator %d scans / %d segment sets, trajectories %d / %d; "
                      "published %d scans, %d trajectories, received %d line_segments" % (
                          self.handled() + (self.diag.counter(MERGING, "trajectories"),
                                            self.diag.counter(EVALUATOR, "trajectories"),
                                            self.scans, self.trajectories, len(self.segments.messages))),
                      self.limit, gone=lt.gone_nodes("/line_segments", "/line_map"))

    def newest_segments(self):
        return self.segments.messages[-1][1].header.stamp.to_sec() if self.segments.messages else float("-inf")

    def wait_extracted(self, stamp, what, step=0.1):
        """Waits for the line_segments of the scan stamped `stamp` (by stamp: a count would also count
        on this process's subscription having been connected from the first message on)."""
        lt.wait_until(lambda: self.newest_segments() >= stamp - 1e-6, "the line_segments of %s (stamp %.3f)"
                      % (what, stamp), lambda: "%d line_segments, the newest stamped %.3f" % (
                          len(self.segments.messages), self.newest_segments()), self.limit, step=step,
                      gone=lt.gone_nodes("/line_segments"))

    def wait_scans_done(self, what):
        self.wait_extracted(self.stamps[-1], "scan %d, the last before %s" % (self.scans, what))
        self.wait_fresh(lambda: self.handled()[0] >= self.scans and self.handled()[1] >= self.scans
                        and self.handled()[2] >= self.scans,
                        "the merger and the evaluator to finish with the %d scans before %s" % (self.scans, what))

    def play(self):
        self.diag.wait_up(lt.Diagnostics.TASKS, self.limit)
        for pub in (self.clock, self.tf, self.scan, self.trajectory):
            lt.wait_until(lambda: pub.get_num_connections() > 0, "a subscriber of " + pub.resolved_name,
                          lambda: "none", self.limit)
        for sub in (self.segments.sub, self.maps.sub, self.qualities.sub):
            lt.wait_until(lambda: sub.get_num_connections() > 0, "a publisher of " + sub.resolved_name,
                          lambda: "none", self.limit)
        with rosbag.Bag(self.bag) as b:
            static = TFMessage()
            for _, msg, _ in b.read_messages(topics=["/tf_static"]):
                static.transforms.extend(msg.transforms)
            self.tf_static.publish(static)
            messages = list(b.read_messages(topics=["/tf", "/scan", "/optimized_trajectory"]))
            early = None  # a /tf message published ahead of its turn
            for i, (topic, msg, t) in enumerate(messages):
                if msg is early:
                    continue
                if topic == "/optimized_trajectory":
                    # A scan published before its transform can be placed only once a transform at or
                    # after its stamp arrives: the next scan's /tf goes first. A lookup at a scan's
                    # stamp is the same with or without it.
                    if i + 1 < len(messages) and messages[i + 1][0] == "/tf":
                        early = messages[i + 1][1]
                        self.clock.publish(Clock(clock=early.transforms[0].header.stamp))
                        self.tf.publish(early)
                    self.wait_scans_done("trajectory %d" % (self.trajectories + 1))
                    self.trajectory.publish(msg)
                    self.trajectories += 1
                    n = self.trajectories
                    self.wait_fresh(lambda: self.diag.counter(MERGING, "trajectories") >= n
                                    and self.diag.counter(EVALUATOR, "trajectories") >= n,
                                    "trajectory %d taken by the merger and the evaluator" % n)
                    continue
                stamp = msg.transforms[0].header.stamp if topic == "/tf" else msg.header.stamp
                self.clock.publish(Clock(clock=stamp))
                (self.tf if topic == "/tf" else self.scan).publish(msg)
                if topic == "/scan":
                    self.scans += 1
                    self.stamps.append(msg.header.stamp.to_sec())
                    # Keep every queue on the way (the publishers' >= 100, the tf waits' 1000) from
                    # overflowing under load: at most 8 scans in flight.
                    if self.scans > 8 and self.newest_segments() < self.stamps[-9] - 1e-6:
                        self.wait_extracted(self.stamps[-3], "scan %d" % (self.scans - 2), step=0.005)
            # The same at the end: a copy of the last /tf 1 ms later lets a scan that came before its
            # transform through; no scan lies between the two samples.
            last_tf = next((m for topic, m, _ in reversed(messages) if topic == "/tf"), None)
            if last_tf is not None:
                import copy
                extra = copy.deepcopy(last_tf)
                for tr in extra.transforms:
                    tr.header.stamp += rospy.Duration(0.001)
                self.clock.publish(Clock(clock=extra.transforms[0].header.stamp))
                self.tf.publish(extra)
        self.wait_scans_done("the end of the bag")


def shown_map(saved):
    """(sorted keyframe stamps, sorted (id, endpoints) of the segments shown) of a saved map file. The
    file holds every map segment; those withheld by the single-view rule are not on line_map."""
    shown = [s for s in saved["segments"] if not s.get("withheld", False)]
    return sorted(k[1] for k in saved["keyframes"]), sorted((s["id"], s["segment"]) for s in shown)


def batch_map(bag, limit):
    """linemap_batch BAG (the default mode) with cae: (keyframe stamps, shown segments) of its map file."""
    out = tempfile.mkdtemp(prefix="parity_batch_")
    rc, log = lt.run(["rosrun", "line_map_eval", "linemap_batch", bag, "--merger", "cae", "--out", out,
                      "--no-figures", "--no-progress"], limit)
    if rc != 0:
        raise AssertionError("linemap_batch failed:\n" + log)
    with open(os.path.join(out, "cae", "map.yaml")) as f:
        return shown_map(yaml.safe_load(f))


def saved_map(path):
    from line_map_msgs.srv import SaveMap
    rospy.wait_for_service("/line_map_merging/save_map", timeout=60.0)
    res = rospy.ServiceProxy("/line_map_merging/save_map", SaveMap)(path=path)
    if not res.success:
        raise RuntimeError("save_map failed: " + res.message)
    with open(path) as f:
        return yaml.safe_load(f)


class CheckParity(unittest.TestCase):
    def test_nodelets_equal_replay(self):
        dataset = rospy.get_param("~dataset")
        band = lt.bands()["parity_" + dataset]
        bag = make_bag(dataset, band)
        n_scans, _, span = lt.bag_scans(bag)
        limit = lt.work_limit(span, band["work_rate"])
        out = tempfile.mkdtemp(prefix="parity_replay_")
        t0 = time.time()
        rc, log = lt.run(["rosrun", "line_map_eval", "linemap_batch", bag, "--replay", "--merger", "cae",
                          "--out", out, "--no-figures"], limit)
        self.assertEqual(rc, 0, log)
        with open(os.path.join(out, "replay.json")) as f:
            replay = json.load(f)
        replay_s = time.time() - t0

        driver = Driver(bag, limit)
        t0 = time.time()
        driver.play()
        nodelet_s = time.time() - t0
        lt.wait_until(lambda: driver.maps.messages, "a line_map", lambda: "none", limit)
        last = driver.maps.messages[-1][1]
        lt.wait_for_quality_of(driver.qualities, last, "the map_quality of the last line_map", limit)
        stamps, segments = shown_map(saved_map(os.path.join(out, "nodelets_map.yaml")))
        self.assertEqual(len(segments), len(last.segments), "the saved map is the last line_map")
        quality = lt.evaluate().quality
        t0 = time.time()
        batch_stamps, batch_segments = batch_map(bag, limit)
        batch_s = time.time() - t0
        print("parity %s (%d scans, %d trajectories): replay %d keyframes, %d segments, %.2f %% (%.1f s); "
              "nodelets %d keyframes, %d segments, %.2f %% (%.1f s driven); batch %d keyframes, %d segments "
              "(%.1f s)" % (
                  dataset, n_scans, driver.trajectories, len(replay["keyframe_stamps"]), len(replay["segments"]),
                  replay["quality"], replay_s, len(stamps), len(segments), quality, nodelet_s, len(batch_stamps),
                  len(batch_segments), batch_s))
        self.assertEqual(driver.trajectories, replay["trajectories"])
        # A segment set the nodelet dropped (no transform in time) would show as a missing keyframe below.
        self.assertEqual(driver.diag.counter(MERGING, "dropped scans"), 0, "the merger dropped segment sets")
        self.assertGreaterEqual(replay["quality"], band["min_quality_pct"])
        replay_stamps = sorted(replay["keyframe_stamps"])
        replay_segments = sorted((s[0], s[1:]) for s in replay["segments"])
        self.assert_same_map("nodelets", stamps, segments, replay_stamps, replay_segments, dataset)
        self.assert_same_map("batch", batch_stamps, batch_segments, replay_stamps, replay_segments, dataset)
        self.assertLessEqual(abs(quality - replay["quality"]), 0.1, "quality differs by more than 0.1 point")

    def assert_same_map(self, who, stamps, segments, replay_stamps, replay_segments, dataset):
        """`who`'s keyframes and map against the replay's: the same stamps, ids, endpoints within 1 mm."""
        self.assertEqual(len(stamps), len(replay_stamps), who + ": keyframe count")
        for a, b in zip(stamps, replay_stamps):
            self.assertAlmostEqual(a, b, delta=1e-6, msg=who + ": keyframe stamps differ")
        self.assertEqual(len(segments), len(replay_segments), who + ": map segment count")
        worst = 0.0
        for (ia, a), (ib, b) in zip(segments, replay_segments):
            self.assertEqual(ia, ib, who + ": map segment ids differ")
            worst = max(worst, max(abs(x - y) for x, y in zip(a, b)))
        print("parity %s, %s against the replay: largest endpoint coordinate difference %.3g m" % (
            dataset, who, worst))
        self.assertLessEqual(worst, 1e-3, who + ": an endpoint differs by more than 1 mm")


if __name__ == "__main__":
    rospy.init_node("check_parity")
    rostest.rosrun("line_map_eval", "check_parity", CheckParity)

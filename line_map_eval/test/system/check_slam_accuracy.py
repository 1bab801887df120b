#!/usr/bin/python3
"""Rostest checker (test/slam_accuracy.test): the laser SLAM's accuracy on real logs. linemap_relations
--slam runs our SLAM (config/slam.yaml, odometry on) on the whole Intel and ACES raw logs; its
trajectory of every scan must meet the logs' relations (Kuemmerle et al., the ground truth of these
logs) to a floor on the mean translation error. The error is computed here from the written trajectory
(lt.relations_error), independently of the tool's own figure, which is printed beside it.

The floors lie between today's SLAM and what a broken one scores (FLOORS below, measured with the
variants named there): a SLAM whose loop closures are off, whose closure gate lets wrong closures in,
or whose front end does not match, misses them."""
import os
import re
import sys
import tempfile
import unittest

import rospy
import rostest

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402

# [m] mean translation error floors, per log. Measured 2026-11-27 on 4f9fdb2 with linemap_relations LOG
# RELATIONS --slam [--param ...], over every relation (Intel 2984, ACES 1279), Intel / ACES:
#   today's SLAM (config/slam.yaml)                                  0.0161 / 0.0372
#   no loop closures (loop/candidates=0)                             0.174  / 0.130
#   closure gate off (loop/consistency_probability=0, min_score=0.3,
#     ambiguity_margin=0, max_error_xy=100, max_error_theta=10)      0.865  / 1.011
#   front end never matches (front_end/min_score=2)                  6.88   / 1.76
#   raw odometry (--odometry)                                        7.37   / 0.549
# Each floor lies well above today's figure (1.5x, 1.3x: the figures moved by up to 0.002 m between the
# SLAM's recent versions) and well below the closest broken variant, no closures (7x, 2.6x). The
# consistency test alone off (loop/consistency_probability=0) is not among them: it refuses no closure
# on these logs (0.0161 / 0.0372 without it); the corridor world (test_laser_slam_corridor) guards it.
FLOORS = {
    "intel": 0.025,
    "aces": 0.05,
}


class CheckSlamAccuracy(unittest.TestCase):
    def check(self, name):
        data = lt.datasets_dir()
        raw, rel = os.path.join(data, name + ".clf.bz2"), os.path.join(data, name + ".relations")
        for f in (raw, rel):
            self.assertTrue(os.path.exists(f), "dataset missing: %s (see ../shared/datasets/README.md)" % f)
        work = tempfile.mkdtemp(prefix="slam_accuracy_")
        trajectory = os.path.join(work, name + ".txt")
        # The bound only catches a hung run; the test waits for the tool to end.
        # The shipped parameters, named: from rostest's working directory the tool would find no
        # config/slam.yaml and run on its built-in defaults.
        config = os.path.join(lt.repo_root(), "config", "slam.yaml")
        rc, log = lt.run(["rosrun", "line_map_eval", "linemap_relations", raw, rel, "--slam", "--no-figures",
                          "--config", config, "--write", trajectory, "--out", work], 1200)
        print(log)
        self.assertEqual(rc, 0, log)
        relations = lt.read_relations(rel)
        mean, count = lt.relations_error(lt.read_trajectory(trajectory), relations)
        tool = re.search(r"^laser SLAM\s+(\d+)/(\d+)\s+([0-9.]+)", log, re.M)
        summary = "%s: laser SLAM relations error %.4f m over %d of %d relations (the tool's: %s), floor %.3f m" % (
            name, mean, count, len(relations), tool.group(3) if tool else "?", FLOORS[name])
        print(summary)
        with open(os.path.join(lt.artifact_dir(), "slam_accuracy_%s.txt" % name), "w") as f:
            f.write(summary + "\n")
        self.assertEqual(count, len(relations), summary)
        self.assertLess(mean, FLOORS[name], summary)

    def test_intel(self):
        self.check("intel")

    def test_aces(self):
        self.check("aces")


if __name__ == "__main__":
    rospy.init_node("check_slam_accuracy", disable_signals=True)
    rostest.rosrun("line_map_eval", "check_slam_accuracy", CheckSlamAccuracy)

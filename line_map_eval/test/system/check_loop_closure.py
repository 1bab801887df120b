#!/usr/bin/python3
"""Rostest checker (test/loop_closure.test): on the simulated loop world (odometry drift of
metres) the optimized_trajectory must improve the map: the share of the map lying on true walls
(python oracle from OUT.truth.yaml) and the evaluator's error against the bands recorded in
test/regression_bands.yaml, and the correlation quality: after the trajectory, the map from before
the loop closure and the adjusted map are both scored against the same corrected scans (the
lookup table is built from the registered, optimised scans, as in the CAE-RLSM paper), and the
adjusted map must score higher by a margin. (Scored against the drifted scans it was built on, the
old map fits them as well as the new one fits the corrected scans: that figure is printed only.)
The checker plays the sensor topics, evaluates (~evaluate), publishes the bag's trajectory itself,
waits for the adjusted map and evaluates again, so every figure belongs to a settled map."""
import os
import sys
import unittest

import rospy
import rostest

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402


class CheckLoopClosure(unittest.TestCase):
    def test_quality_rises_with_the_loop_closure(self):
        band = lt.bands()["loop_closure"]
        bag, truth_path, log = lt.simulate("loop", band["seed"], band["scans"], "loop_closure_")
        run = lt.BagRun(bag, band["rate"])
        map_before = run.play()
        before = lt.evaluate()
        adjusted = run.close_loop()
        after = lt.evaluate()
        before_corrected = lt.evaluate(map_before)
        truth = lt.load_truth(truth_path)
        p_before = lt.precision(truth, lt.map_segments(map_before))
        p_after = lt.precision(truth, lt.map_segments(adjusted))
        print("loop: map length on true walls before %.1f %%, after %.1f %%" % (100 * p_before, 100 * p_after))
        print("loop: quality against the corrected scans: map before the closure %.2f %% (%d segments), after "
              "%.2f %% (%d segments, error %.2f mm); the map before against its own drifted scans %.2f %% (error "
              "%.2f mm)\n%s" % (before_corrected.quality, before_corrected.segment_count, after.quality,
                                after.segment_count, 1e3 * after.error, before.quality, 1e3 * before.error, log))
        self.assertLessEqual(p_before, band["max_on_walls_before"])
        self.assertGreaterEqual(p_after, band["min_on_walls_after"])
        self.assertGreaterEqual(p_after - p_before, band["min_on_walls_gain"])
        self.assertGreaterEqual(before.error, band["min_error_before_m"])
        self.assertLessEqual(after.error, band["max_error_after_m"])
        self.assertLess(after.segment_count, before.segment_count, "the closed loop must merge doubled walls")
        self.assertGreaterEqual(after.quality, band["min_quality_after_pct"])
        self.assertGreaterEqual(after.quality, before_corrected.quality + band["min_quality_gain_pct"],
                                "the adjusted map must fit the corrected scans better than the map before it")


if __name__ == "__main__":
    rospy.init_node("check_loop_closure")
    rostest.rosrun("line_map_eval", "check_loop_closure", CheckLoopClosure)

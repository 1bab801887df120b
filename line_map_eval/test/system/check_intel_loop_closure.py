#!/usr/bin/python3
"""Rostest checker (test/intel_loop_closure.test): converts a prefix of the Intel raw log with
its corrected trajectory (carmen_to_bag --corrected --every 50), plays the sensor topics (raw
odometry), evaluates, publishes the last corrected trajectory of the prefix and evaluates again.
Against the corrected scans, the adjusted map must score higher than the map from before the
trajectory by the margin recorded in test/regression_bands.yaml, stay above a floor, and doubled
walls must merge."""
import os
import sys
import tempfile
import unittest

import rospy
import rostest

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402


class CheckIntelLoopClosure(unittest.TestCase):
    def test_corrected_trajectory_merges_the_map(self):
        band = lt.bands()["intel_loop_closure"]
        raw = os.path.join(lt.datasets_dir(), "intel.clf.bz2")
        corrected = os.path.join(lt.datasets_dir(), "intel-corrected.log.gz")
        if not (os.path.exists(raw) and os.path.exists(corrected)):
            self.skipTest("Intel dataset missing under " + lt.datasets_dir())
        bag = os.path.join(tempfile.mkdtemp(prefix="intel_loop_closure_"), "intel.bag")
        rc, log = lt.run(["rosrun", "line_map_eval", "carmen_to_bag", raw, bag, "--corrected", corrected,
                          "--every", "50", "--max-scans", str(band["max_scans"])], 600)
        self.assertEqual(rc, 0, log)
        run = lt.BagRun(bag, band["rate"])
        map_before = run.play()
        before = lt.evaluate()
        run.close_loop()
        after = lt.evaluate()
        before_corrected = lt.evaluate(map_before)
        print("intel (%d scans): quality against the corrected scans: map before the trajectory %.2f %% (%d "
              "segments), after %.2f %% (%d segments, error %.2f mm); the map before against its own odometry "
              "scans %.2f %% (error %.2f mm)" % (band["max_scans"], before_corrected.quality,
                                                before_corrected.segment_count, after.quality, after.segment_count,
                                                1e3 * after.error, before.quality, 1e3 * before.error))
        self.assertGreaterEqual(after.quality, band["min_quality_after_pct"])
        self.assertGreaterEqual(after.quality, before_corrected.quality + band["min_quality_gain_pct"],
                                "the adjusted map must fit the corrected scans better than the map before it")
        self.assertLessEqual(after.segment_count, band["max_segment_ratio_after"] * before.segment_count)


if __name__ == "__main__":
    rospy.init_node("check_intel_loop_closure")
    rostest.rosrun("line_map_eval", "check_intel_loop_closure", CheckIntelLoopClosure)

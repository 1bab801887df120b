#!/usr/bin/python3
"""Rostest checker (test/batch_intel.test): runs linemap_batch on the Intel corrected keyframes
for every merger and compares report.json with the bands of test/regression_bands.yaml."""
import json
import os
import sys
import tempfile
import unittest

import rospy
import rostest

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402


class CheckBatchIntel(unittest.TestCase):
    def test_every_merger_within_its_band(self):
        band = lt.bands()["batch_intel"]
        dataset = os.path.join(lt.datasets_dir(), band["dataset"])
        if not os.path.exists(dataset):
            self.skipTest("dataset missing: " + dataset)
        out = tempfile.mkdtemp(prefix="batch_intel_")
        cmd = ["rosrun", "line_map_eval", "linemap_batch", dataset, "--out", out, "--no-progress", "--no-figures"]
        for name in band["mergers"]:
            cmd += ["--merger", name]
        rc, log = lt.run(cmd, 240)
        self.assertEqual(rc, 0, log)
        print(log)
        with open(os.path.join(out, "report.json")) as f:
            report = json.load(f)
        problems = []
        for name, b in band["mergers"].items():
            self.assertIn(name, report["mergers"], "merger missing from report.json")
            r = report["mergers"][name]
            if not b["map_segments"][0] <= r["map_segments"] <= b["map_segments"][1]:
                problems.append("%s: %d map segments outside %s" % (name, r["map_segments"], b["map_segments"]))
            if r["quality_pct"] < b["min_quality_pct"]:
                problems.append("%s: quality %.2f %% < %.2f %%" % (name, r["quality_pct"], b["min_quality_pct"]))
            if r["error_mm"] > b["max_error_mm"]:
                problems.append("%s: error %.2f mm > %.2f mm" % (name, r["error_mm"], b["max_error_mm"]))
            # A map must not score by leaving walls out.
            for key in ("point_coverage_pct", "length_coverage_pct"):
                if not band["min_" + key] <= r[key] <= 100.0:
                    problems.append("%s: %s %.2f outside [%.1f, 100]" % (name, key, r[key], band["min_" + key]))
            for key in ("redundant_pairs", "unassigned_originals"):
                if not isinstance(r.get(key), int) or r[key] < 0:
                    problems.append("%s: %s missing or negative: %r" % (name, key, r.get(key)))
        cae = report["mergers"].get("cae")
        if cae is not None:
            for other in band.get("cae_not_below", []):
                if other in report["mergers"] and cae["quality_pct"] < report["mergers"][other]["quality_pct"]:
                    problems.append("cae: quality %.2f %% below %s's %.2f %%"
                                    % (cae["quality_pct"], other, report["mergers"][other]["quality_pct"]))
            if cae["redundant_pairs"] > band.get("cae_max_redundant_pairs", 0):
                problems.append("cae: %d redundant pairs left" % cae["redundant_pairs"])
            # Issue 22: the map covers the straight structure and draws no X.
            crossing, most = cae.get("crossing_pairs"), band.get("cae_max_crossing_pairs", 0)
            if not isinstance(crossing, int) or not 0 <= crossing <= most:
                problems.append("cae: crossing pairs %r, at most %d allowed" % (crossing, most))
            if cae.get("structure_coverage_pct", 0.0) < band["cae_min_structure_coverage_pct"]:
                problems.append("cae: structure coverage %.2f %% < %.1f %%"
                                % (cae.get("structure_coverage_pct", 0.0), band["cae_min_structure_coverage_pct"]))
        self.assertFalse(problems, "\n".join(problems))


if __name__ == "__main__":
    rospy.init_node("check_batch_intel", disable_signals=True)
    rostest.rosrun("line_map_eval", "check_batch_intel", CheckBatchIntel)

#!/usr/bin/python3
"""Rostest checker (test/office_pipeline.test): the simulated office through linemap.launch. After
the bag and its loop closure the map quality, the segment count and the coverage of every seen
true wall (computed here from OUT.truth.yaml, independently of the C++ metrics) must stay within
the bands of test/regression_bands.yaml."""
import os
import sys
import unittest

import rospy
import rostest

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402


class CheckOfficePipeline(unittest.TestCase):
    def test_coverage_oracle(self):
        # The oracle itself: the true walls cover themselves; walls moved by 10 cm or turned by
        # 90 degrees cover nothing; half a wall covers half.
        wall = [0.0, 0.0, 4.0, 0.0]
        self.assertAlmostEqual(lt.coverage(wall, [[0.0, 4.0]], [wall]), 1.0)
        self.assertEqual(lt.coverage(wall, [[0.0, 4.0]], [[0.0, 0.1, 4.0, 0.1]]), 0.0)
        self.assertEqual(lt.coverage(wall, [[0.0, 4.0]], [[2.0, -1.0, 2.0, 1.0]]), 0.0)
        # 2 m of segment 2 cm off the wall: covered up to sqrt(5^2 - 2^2) cm beyond its end.
        self.assertAlmostEqual(lt.coverage(wall, [[0.0, 4.0]], [[4.0, 0.02, 2.0, 0.02]]),
                               (2.0 + (0.05**2 - 0.02**2)**0.5) / 4.0, delta=0.005)
        truth = {"walls": [wall, [0, 1, 0, 2]],
                 "scans": [{"visible": [{"wall": 0, "segment": [0.5, 0, 1.2, 0], "beams": 20}]},
                           {"visible": [{"wall": 0, "segment": [1.0, 0, 1.6, 0], "beams": 20},
                                        {"wall": 1, "segment": [0, 1, 0, 1.5], "beams": 20}]}]}
        seen = lt.seen_walls(truth, 1.0)
        self.assertEqual(len(seen), 1)
        self.assertEqual(seen[0][0], 0)
        self.assertAlmostEqual(seen[0][2][0][0], 0.5)
        self.assertAlmostEqual(seen[0][2][0][1], 1.6)

    def test_office_after_loop_closure(self):
        band = lt.bands()["office_pipeline"]
        bag, truth_path, _ = lt.simulate("office", band["seed"], band["scans"], "office_pipeline_")
        run = lt.BagRun(bag, band["rate"])
        run.play()
        final_map = run.close_loop()
        quality = run.quality_of(final_map)
        segments = lt.map_segments(final_map)

        truth = lt.load_truth(truth_path)
        seen = lt.seen_walls(truth, band["min_seen_wall_m"], band["piece_min_beams"], band["piece_min_length_m"],
                             band["piece_max_spacing_m"])
        with open(os.path.join(lt.artifact_dir(), "office_pipeline_map.yaml"), "w") as f:
            f.write("# final line_map of test/office_pipeline.test: [x0, y0, x1, y1]\nsegments:\n")
            f.writelines("  - [%.4f, %.4f, %.4f, %.4f]\n" % s for s in segments)
        worst = (1.0, None)
        poor = []
        for w, wall, intervals in seen:
            c, gaps = lt.coverage(wall, intervals, segments, band["coverage_distance_m"], return_gaps=True)
            if c < worst[0]:  # (not min() of tuples: a tie at 1.0 would compare an index with None)
                worst = (c, w)
            if c < band["min_wall_coverage"]:
                poor.append("wall %d %s: %.1f %%, uncovered %s" % (w, wall, 100.0 * c, [[round(a, 2), round(b, 2)] for a, b in gaps]))
        print("office: %d map segments, quality %.2f %%, error %.2f mm, %d seen walls, worst coverage %.1f %% "
              "(wall %s)" % (len(segments), quality.quality, 1000.0 * quality.error, len(seen),
                             100.0 * worst[0], worst[1]))
        self.assertGreaterEqual(len(seen), band["min_seen_walls"])
        self.assertGreaterEqual(quality.quality, band["min_quality_pct"])
        self.assertGreaterEqual(len(segments), band["segments"][0])
        self.assertLessEqual(len(segments), band["segments"][1])
        self.assertFalse(poor, "walls covered less than %.0f %%:\n%s" % (100.0 * band["min_wall_coverage"],
                                                                         "\n".join(poor)))


if __name__ == "__main__":
    rospy.init_node("check_office_pipeline")
    rostest.rosrun("line_map_eval", "check_office_pipeline", CheckOfficePipeline)

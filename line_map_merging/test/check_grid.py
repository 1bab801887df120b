#!/usr/bin/python3
"""Rostest checker of the merging nodelet's occupancy grid (grid.test): drives the corridor of
check_merging.py (two walls at y = +-2 m), and checks that no grid is built while nobody subscribes
(the nodelet's diagnostics count them), that a late subscriber gets the current map's grid, that
further keyframes give a grid of the newest map but at most one per grid_period, and that each grid
has the parameters' resolution, covers the map plus its margin, marks occupied exactly the cells on
the line map's segments (within one cell), free the corridor and unknown beyond the walls."""
import math
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from line_map_msgs.msg import LineMap
from nav_msgs.msg import OccupancyGrid

from check_merging import LIMIT, STEP, connect_to_merger, segments_seen_from, transform

RESOLUTION = 0.1  # grid.test's grid_resolution
PERIOD = 1.0      # grid.test's grid_period
MARGIN = 0.25     # OccupancyGridParams::margin


def distance_to_segment(px, py, s):
    ax, ay, bx, by = s.start.x, s.start.y, s.end.x, s.end.y
    dx, dy = bx - ax, by - ay
    t = max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy)))
    return math.hypot(px - ax - t * dx, py - ay - t * dy)


class CheckGrid(unittest.TestCase):
    def setUp(self):
        self.maps = []
        rospy.Subscriber("line_map", LineMap, self.maps.append)
        self.grids_published = []  # (receipt time, the diagnostics' count)
        rospy.Subscriber("diagnostics", DiagnosticArray, self.on_diagnostics)
        self.grids = []  # (receipt time, grid)
        connect_to_merger(self)
        self.stamp = rospy.Time.now()

    def on_diagnostics(self, msg):
        for status in msg.status:
            for kv in status.values:
                if kv.key == "grids published":
                    self.grids_published.append((time.time(), int(kv.value)))

    def wait_until(self, predicate, what):
        deadline = time.time() + LIMIT
        while not predicate():
            self.assertLess(time.time(), deadline, "waited %.0f s for %s" % (LIMIT, what))
            time.sleep(0.02)

    def drive(self, first, count):
        """Scans at x = STEP * i for i in [first, first + count): each a keyframe."""
        for i in range(first, first + count):
            self.stamp += rospy.Duration(0.1)
            self.tf.sendTransform(transform("map", "base_link", self.stamp, STEP * i, 0.0, 0.0))
            self.pub.publish(segments_seen_from(STEP * i, self.stamp))
            time.sleep(0.05)
        self.wait_until(lambda: self.maps and self.maps[-1].keyframes == first + count,
                        "the map of %d keyframes" % (first + count))
        return self.maps[-1]

    def check_grid(self, grid, m):
        """`grid` is the grid of line map `m`."""
        info = grid.info
        self.assertEqual(grid.header.frame_id, "map")
        # The newest keyframe's stamp: the last scan's (every scan is a keyframe), as on line_map.
        self.assertEqual(grid.header.stamp, m.header.stamp)
        self.assertAlmostEqual(info.resolution, RESOLUTION, delta=1e-6)
        self.assertEqual(len(grid.data), info.width * info.height)
        # The map's extent plus the margin (the keyframe poses lie inside it here), in whole cells.
        xs = [p.x for s in m.segments for p in (s.segment.start, s.segment.end)]
        ys = [p.y for s in m.segments for p in (s.segment.start, s.segment.end)]
        first_x, first_y = math.floor((min(xs) - MARGIN) / RESOLUTION), math.floor((min(ys) - MARGIN) / RESOLUTION)
        self.assertAlmostEqual(info.origin.position.x, first_x * RESOLUTION, delta=1e-6)
        self.assertAlmostEqual(info.origin.position.y, first_y * RESOLUTION, delta=1e-6)
        self.assertEqual(info.width, math.floor((max(xs) + MARGIN) / RESOLUTION) + 1 - first_x)
        self.assertEqual(info.height, math.floor((max(ys) + MARGIN) / RESOLUTION) + 1 - first_y)
        ox, oy, w = info.origin.position.x, info.origin.position.y, info.width

        def centre(i):
            return ox + (i % w + 0.5) * RESOLUTION, oy + (i // w + 0.5) * RESOLUTION

        def cell(x, y):
            return int(math.floor((x - ox) / RESOLUTION)), int(math.floor((y - oy) / RESOLUTION))

        def value(x, y):
            column, row = cell(x, y)
            return grid.data[row * w + column]

        # Every occupied cell on a segment (its centre within one cell of it), every segment occupied.
        occupied = [i for i, v in enumerate(grid.data) if v == 100]
        self.assertTrue(occupied)
        occupied_cells = {(i % w, i // w) for i in occupied}
        for i in occupied:
            x, y = centre(i)
            self.assertLessEqual(min(distance_to_segment(x, y, s.segment) for s in m.segments), RESOLUTION,
                                 "occupied cell (%.2f, %.2f) on no segment" % (x, y))
        length = sum(math.hypot(s.segment.end.x - s.segment.start.x, s.segment.end.y - s.segment.start.y)
                     for s in m.segments)
        self.assertLessEqual(len(occupied), length / RESOLUTION + 2 * len(m.segments))
        for s in m.segments:
            n = int(math.hypot(s.segment.end.x - s.segment.start.x, s.segment.end.y - s.segment.start.y) / 0.02)
            for k in range(n + 1):
                x = s.segment.start.x + (s.segment.end.x - s.segment.start.x) * k / n
                y = s.segment.start.y + (s.segment.end.y - s.segment.start.y) * k / n
                # Its cell, or the next one where the point lies on a cell boundary.
                column, row = cell(x, y)
                self.assertTrue(any((column + dc, row + dr) in occupied_cells for dc in (-1, 0, 1) for dr in (-1, 0, 1)),
                                "(%.2f, %.2f) on a segment is not occupied" % (x, y))
        # Free between the walls where the robot drove (seen from the keyframes; away from the
        # triangles' apexes at the laser), unknown beyond them. Off the cell boundaries.
        for x in (0.03, 1.03, STEP * (m.keyframes - 1) + 0.03):
            for y in (-1.53, -1.03, 1.03, 1.53):
                self.assertEqual(value(x, y), 0, "(%.2f, %.2f) in the corridor is not free" % (x, y))
            for y in (-2.17, 2.17):
                self.assertEqual(value(x, y), -1, "(%.2f, %.2f) behind a wall is not unknown" % (x, y))

    def test_grid(self):
        # No subscriber: the map grows, no grid is built. The second diagnostics report after the last
        # map is at least a report period (1 s) later, many grid ticks (0.1 s).
        m = self.drive(0, 20)
        received = time.time()
        self.wait_until(lambda: sum(1 for t, _ in self.grids_published if t > received) >= 2,
                        "two diagnostics reports after the map")
        self.assertEqual(self.grids_published[-1][1], 0, "grids built while nobody subscribed")

        # A late subscriber gets the current map's grid.
        rospy.Subscriber("grid", OccupancyGrid, lambda g: self.grids.append((time.time(), g)))
        self.wait_until(lambda: self.grids, "a grid for the late subscriber")
        self.check_grid(self.grids[0][1], m)

        # More keyframes: grids follow the map, the last one of the newest map, but grids start at least
        # grid_period apart, so no more than (t1 - t0) / period + 1 of them arrive in [t0, t1].
        t0 = time.time()
        m = self.drive(20, 15)
        self.wait_until(lambda: self.grids[-1][1].header.stamp == m.header.stamp, "the grid of the newest map")
        t1 = time.time()
        during = [g for t, g in self.grids if t > t0]
        self.assertGreaterEqual(len(during), 1)
        self.assertLessEqual(len(during), (t1 - t0) / PERIOD + 1,
                             "%d grids in %.2f s with grid_period %.1f s" % (len(during), t1 - t0, PERIOD))
        self.check_grid(self.grids[-1][1], m)


if __name__ == "__main__":
    rospy.init_node("check_grid")
    rostest.rosrun("line_map_merging", "check_grid", CheckGrid)

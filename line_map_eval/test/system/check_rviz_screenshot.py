#!/usr/bin/python3
"""Rostest checker (test/rviz_screenshot.test): starts Xvfb on a free display and RViz with
rviz/linemap.rviz, replays the simulated office through the pipeline, takes a screenshot with
imagemagick's import and checks that the merger's marker colours (start points red 1.0/0/0, end
points green 0/0.8/0, line_map_merging/src/ros/nodelet.cpp) appear in the 3D view."""
import os
import shutil
import signal
import subprocess
import sys
import unittest

import rospy
import rostest
import yaml
from visualization_msgs.msg import MarkerArray

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402

MIN_PIXELS = 30  # of each colour; the office map shows about 80 of each (measured)
PANEL_WIDTH = 365  # the Displays panel (when shown) holds red/green icons: only x beyond it counts


def marker_only_config(out_dir):
    """rviz/linemap.rviz with the displays that share the markers' hues switched off: the scan
    (orange points) and the optimised trajectory (green line)."""
    with open(os.path.join(lt.repo_root(), "rviz", "linemap.rviz")) as f:
        config = yaml.safe_load(f)
    for d in config["Visualization Manager"]["Displays"]:
        if d["Class"] in ("rviz/LaserScan", "rviz/Path"):
            d["Enabled"] = False
    path = os.path.join(out_dir, "linemap_markers.rviz")
    with open(path, "w") as f:
        yaml.safe_dump(config, f)
    return path


def free_display():
    for n in range(90, 200):
        if not os.path.exists("/tmp/.X%d-lock" % n) and not os.path.exists("/tmp/.X11-unix/X%d" % n):
            return n
    raise RuntimeError("no free X display number in 90..199")


def read_ppm(data):
    """(width, height, bytes) of a binary PPM (P6, maxval 255)."""
    fields, pos = [], 0
    while len(fields) < 4:
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos)
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[pos:end])
        pos = end
    assert fields[0] == b"P6" and fields[3] == b"255", fields
    return int(fields[1]), int(fields[2]), data[pos + 1:]


def subscribers(topic):
    """Names of the nodes subscribed to `topic`, from the master."""
    import rosgraph
    _, subs, _ = rosgraph.Master("/check_rviz_screenshot").getSystemState()
    return next((nodes for name, nodes in subs if name == topic), [])


def count_colours(width, height, pixels, x_min):
    red = green = 0
    for y in range(height):
        row = pixels[3 * width * y:3 * width * (y + 1)]
        for x in range(x_min, width):
            r, g, b = row[3 * x], row[3 * x + 1], row[3 * x + 2]
            # The points are 2 px wide and antialiased against white: hue, not the exact value.
            if r >= 160 and g <= 100 and b <= 100:
                red += 1
            elif g >= 150 and r <= 100 and b <= 100:
                green += 1
    return red, green


class CheckRvizScreenshot(unittest.TestCase):
    def setUp(self):
        self.procs = []

    def tearDown(self):
        for p in reversed(self.procs):
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
                try:
                    p.wait(10)
                except subprocess.TimeoutExpired:
                    p.kill()

    def test_screenshot_shows_the_map(self):
        bag, _, _ = lt.simulate("office", 5, 300, "rviz_screenshot_")
        display = ":%d" % free_display()
        env = dict(os.environ, DISPLAY=display)
        self.procs.append(subprocess.Popen(["Xvfb", display, "-screen", "0", "1280x800x24", "-nolisten", "tcp"],
                                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        run = lt.BagRun(bag, 8)
        lt.wait_until(lambda: os.path.exists("/tmp/.X11-unix/X" + display[1:]), "Xvfb's socket on " + display,
                      lambda: "none", run.limit)
        log = open(os.path.join(lt.artifact_dir(), "rviz_screenshot_rviz.log"), "w")
        self.procs.append(subprocess.Popen(["rviz", "-d", marker_only_config(os.path.dirname(bag)),
                                            "__name:=rviz_screenshot_rviz"], env=env, stdout=log,
                                           stderr=subprocess.STDOUT))
        markers = lt.Collector("line_map_markers", MarkerArray)
        # RViz up and subscribed (the merger publishes its markers only while someone subscribes).
        lt.wait_until(lambda: self.procs[-1].poll() is not None or "/rviz_screenshot_rviz" in subscribers(
            "/line_map_markers"), "RViz to subscribe to line_map_markers",
            lambda: "subscribers %s" % subscribers("/line_map_markers"), run.limit)
        self.assertIsNone(self.procs[-1].poll(), "rviz exited, see rviz_screenshot_rviz.log")
        final_map = run.play()
        lt.wait_until(lambda: any(m.markers and m.markers[0].header.stamp == final_map.header.stamp
                                  for _, m in markers.messages[-3:]),
                      "the line_map_markers of the final map", lambda: "%d line_map_markers messages"
                      % len(markers.messages), run.limit)

        # RViz renders at 30 Hz: screenshots until the markers show (the event), within the limit.
        png = os.path.join(lt.artifact_dir(), "rviz_linemap.png")
        shot = {"red": 0, "green": 0, "size": (0, 0), "n": 0}

        def markers_visible():
            rc, out = lt.run(["import", "-display", display, "-window", "root", png], 60)
            self.assertEqual(rc, 0, out)
            ppm = subprocess.run(["convert", png, "ppm:-"], stdout=subprocess.PIPE, check=True, timeout=60).stdout
            width, height, pixels = read_ppm(ppm)
            shot["red"], shot["green"] = count_colours(width, height, pixels, PANEL_WIDTH)
            shot["size"], shot["n"] = (width, height), shot["n"] + 1
            return shot["red"] >= MIN_PIXELS and shot["green"] >= MIN_PIXELS

        try:
            lt.wait_until(markers_visible, "%d red and %d green marker pixels in the screenshot" % (
                MIN_PIXELS, MIN_PIXELS), lambda: "%d red, %d green in screenshot %d" % (
                shot["red"], shot["green"], shot["n"]), run.limit, step=0.5)
        except AssertionError:
            pass  # the assertions below say which colour is missing
        red, green = shot["red"], shot["green"]
        print("RViz screenshot: " + png)
        print("RViz screenshot %dx%d: %d red (start point) and %d green (end point) pixels right of x=%d"
              % (shot["size"][0], shot["size"][1], red, green, PANEL_WIDTH))
        self.assertGreaterEqual(red, MIN_PIXELS, "no start point markers visible in " + png)
        self.assertGreaterEqual(green, MIN_PIXELS, "no end point markers visible in " + png)


if __name__ == "__main__":
    if not shutil.which("Xvfb") or not shutil.which("import"):
        sys.exit("Xvfb and imagemagick's import are required (scripts/setup.sh)")
    rospy.init_node("check_rviz_screenshot")
    rostest.rosrun("line_map_eval", "check_rviz_screenshot", CheckRvizScreenshot)

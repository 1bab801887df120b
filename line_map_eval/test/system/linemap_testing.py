"""Shared helpers of the system-level rostests (test/*.test at the repository root): simulated
bags, the ground-truth wall coverage oracle, topic collection, the recorded regression bands and
the test artefact directory. Imported by the checker scripts next to this file."""
import math
import os
import subprocess
import tempfile
import time

import rospkg
import rospy
import yaml


def repo_root():
    return os.path.normpath(os.path.join(rospkg.RosPack().get_path("line_map_eval"), ".."))


def datasets_dir():
    return os.path.normpath(os.path.join(repo_root(), "..", "shared", "datasets"))


def bands():
    """The reviewed regression bands (test/regression_bands.yaml)."""
    with open(os.path.join(repo_root(), "test", "regression_bands.yaml")) as f:
        return yaml.safe_load(f)


def artifact_dir():
    """<BUILD_DIR>/test_artifacts: BUILD_DIR from the environment, else ROS_HOME's parent."""
    build = os.environ.get("BUILD_DIR")
    if build:
        if not os.path.isabs(build):
            build = os.path.join(repo_root(), build)
    elif os.environ.get("ROS_HOME"):
        build = os.path.dirname(os.path.normpath(os.environ["ROS_HOME"]))
    else:
        build = tempfile.gettempdir()
    out = os.path.join(build, "test_artifacts")
    os.makedirs(out, exist_ok=True)
    return out


def run(cmd, timeout):
    """Runs a command; returns (returncode, combined output)."""
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=timeout)
    return p.returncode, p.stdout.decode(errors="replace")


def simulate(world, seed, scans, prefix="system_", extra=()):
    """Simulates config/worlds/<world>.yaml into a temporary bag; returns (bag, truth yaml path, log)."""
    bag = os.path.join(tempfile.mkdtemp(prefix=prefix), world + ".bag")
    rc, out = run(["rosrun", "line_map_eval", "simulate_world",
                   os.path.join(repo_root(), "config", "worlds", world + ".yaml"), bag,
                   "--seed", str(seed), "--scans", str(scans), "--no-progress"] + list(extra), 120)
    if rc != 0:
        raise RuntimeError("simulate_world failed:\n" + out)
    return bag, bag[:-len(".bag")] + ".truth.yaml", out


def play(bag, rate, timeout=240, topics=None):
    """rosbag play --clock; raises with its output on failure."""
    cmd = ["rosbag", "play", "--clock", "--quiet", "--rate", str(rate), bag]
    if topics:
        cmd += ["--topics"] + list(topics)
    rc, out = run(cmd, timeout)
    if rc != 0:
        raise RuntimeError("rosbag play failed:\n" + out)


def wait_for(predicate, timeout, step=0.1):
    deadline = time.time() + timeout
    while time.time() < deadline:
        if predicate():
            return True
        time.sleep(step)
    return predicate()


class Collector:
    """Keeps every message of a topic, tagged with how many optimized_trajectory messages came before."""

    def __init__(self, topic, msg_type, epoch=None):
        self.messages = []
        self._epoch = epoch
        self.sub = rospy.Subscriber(topic, msg_type, self._cb, queue_size=100)

    def _cb(self, msg):
        self.messages.append((len(self._epoch.messages) if self._epoch else 0, msg))

    def before(self, n=1):
        return [m for e, m in self.messages if e < n]

    def after(self, n=1):
        return [m for e, m in self.messages if e >= n]


# ---- ground-truth wall coverage (independent of the C++ metrics) ----

def load_truth(path):
    with open(path) as f:
        return yaml.safe_load(f)


def _project(wall, p):
    """Parameter of p along the wall, in metres from its start."""
    x0, y0, x1, y1 = wall
    length = math.hypot(x1 - x0, y1 - y0)
    return ((p[0] - x0) * (x1 - x0) + (p[1] - y0) * (y1 - y0)) / length


def _union(intervals):
    out = []
    for a, b in sorted(intervals):
        if out and a <= out[-1][1]:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return out


def seen_walls(truth, min_length=1.0, piece_beams=0, piece_length=0.0, piece_spacing=float("inf")):
    """Walls whose visible pieces (over all scans) total at least min_length metres:
    list of (wall index, wall [x0,y0,x1,y1], union of seen intervals along the wall).
    Only pieces an extractor can turn into a segment count: at least piece_beams hits, at least
    piece_length long, at most piece_spacing metres between neighbouring hits on average."""
    pieces = {}
    for scan in truth["scans"]:
        for v in scan.get("visible") or []:
            wall = truth["walls"][v["wall"]]
            s = v["segment"]
            a, b = sorted((_project(wall, s[0:2]), _project(wall, s[2:4])))
            if v["beams"] < piece_beams or b - a < piece_length or \
                    (b - a) / max(1, v["beams"] - 1) > piece_spacing:
                continue
            pieces.setdefault(v["wall"], []).append((a, b))
    out = []
    for w, iv in sorted(pieces.items()):
        u = _union(iv)
        if sum(b - a for a, b in u) >= min_length:
            out.append((w, truth["walls"][w], u))
    return out


def _point_segment_distance(px, py, s):
    x0, y0, x1, y1 = s
    dx, dy = x1 - x0, y1 - y0
    l2 = dx * dx + dy * dy
    t = 0.0 if l2 == 0.0 else max(0.0, min(1.0, ((px - x0) * dx + (py - y0) * dy) / l2))
    return math.hypot(px - (x0 + t * dx), py - (y0 + t * dy))


def coverage(wall, intervals, segments, distance=0.05, max_angle=math.radians(10.0), step=0.01,
             return_gaps=False):
    """Fraction of the seen part of a wall whose points lie within `distance` of a map segment
    whose direction differs from the wall's by at most max_angle (undirected); with return_gaps
    also the uncovered stretches [from, to] in metres along the wall."""
    x0, y0, x1, y1 = wall
    length = math.hypot(x1 - x0, y1 - y0)
    ux, uy = (x1 - x0) / length, (y1 - y0) / length
    wall_angle = math.atan2(uy, ux)
    near = []
    for s in segments:
        d = abs(math.remainder(math.atan2(s[3] - s[1], s[2] - s[0]) - wall_angle, math.pi))
        if d <= max_angle:
            near.append(s)
    total = covered = 0
    gaps = []
    for a, b in intervals:
        n = max(1, int(round((b - a) / step)))
        for i in range(n):
            t = a + (i + 0.5) * (b - a) / n
            px, py = x0 + t * ux, y0 + t * uy
            total += 1
            if any(_point_segment_distance(px, py, s) <= distance for s in near):
                covered += 1
            elif gaps and abs(gaps[-1][1] - t) <= 1.5 * (b - a) / n:
                gaps[-1][1] = t
            else:
                gaps.append([t, t])
    if return_gaps:
        return (covered / total if total else 1.0), gaps
    return covered / total if total else 1.0


def map_segments(line_map):
    return [(s.segment.start.x, s.segment.start.y, s.segment.end.x, s.segment.end.y) for s in line_map.segments]


# ---- the loop closure driven by the checker ----

SENSOR_TOPICS = ("/scan", "/tf", "/tf_static")


def bag_trajectories(bag):
    """The optimized_trajectory messages of a bag, in order."""
    import rosbag
    with rosbag.Bag(bag) as b:
        return [m for _, m, _ in b.read_messages(topics=["/optimized_trajectory", "optimized_trajectory"])]


def evaluate(given_map=None, timeout=10.0):
    """Calls /line_map_eval/evaluate; returns line_map_msgs/MapQuality. With `given_map` (a
    line_map_msgs/LineMap) that map is scored against the evaluator's current (registered) scans
    instead of the latest line_map."""
    from line_map_msgs.srv import Evaluate
    rospy.wait_for_service("/line_map_eval/evaluate", timeout=timeout)
    proxy = rospy.ServiceProxy("/line_map_eval/evaluate", Evaluate)
    res = proxy() if given_map is None else proxy(use_given_map=True, map=given_map)
    if not res.success:
        raise RuntimeError("evaluate failed: " + res.message)
    return res.quality


def wait_for_new_map(maps, count, timeout=20.0, settle=1.0):
    """Waits for a line_map beyond the first `count` messages, then until none came for `settle` s."""
    if not wait_for(lambda: len(maps.messages) > count, timeout):
        return False
    while True:
        n = len(maps.messages)
        time.sleep(settle)
        if len(maps.messages) == n:
            return True


def precision(truth, segments, distance=0.1):
    """Fraction of the map's segment length lying within `distance` of a true wall of similar
    direction: drifted, doubled walls lower it."""
    total = near = 0.0
    for s in segments:
        length = math.hypot(s[2] - s[0], s[3] - s[1])
        if length == 0.0:
            continue
        best = 0.0
        c = coverage(list(s), [[0.0, length]], truth["walls"], distance)
        best = max(best, c)
        total += length
        near += best * length
    return near / total if total else 0.0

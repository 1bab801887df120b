"""Shared helpers of the system-level rostests (test/*.test at the repository root): simulated
bags, the ground-truth wall coverage oracle, topic collection, the recorded regression bands and
the test artefact directory. Imported by the checker scripts next to this file."""
import math
import os
import re
import struct
import subprocess
import sys
import tempfile
import time
import zlib

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
    """Runs a command in a process group of its own; returns (returncode, combined output). On reaching the
    timeout the whole group is killed and subprocess.TimeoutExpired raised: killing the command alone leaves
    a child of a wrapper (rosbag play's player) holding the output open, and the read would never end."""
    import signal
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        out, _ = p.communicate(timeout=within_budget(timeout))
    except BaseException:
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        p.communicate()
        raise
    return p.returncode, out.decode(errors="replace")


def stamp_key(stamp):
    """A log stamp as a key: a tenth of a millisecond tells the scans apart and survives float rounding."""
    return round(stamp, 4)


def read_relations(path):
    """The relations file of a log (Kuemmerle et al.): (t1 key, t2 key, x, y, yaw) per line."""
    with open(path) as f:
        return [(stamp_key(float(v[0])), stamp_key(float(v[1])), float(v[2]), float(v[3]), float(v[7]))
                for v in (line.split() for line in f) if v]


def read_trajectory(path):
    """A trajectory as linemap_relations --write writes it ("stamp x y theta" per scan): {stamp key: pose}."""
    with open(path) as f:
        return {stamp_key(float(v[0])): (float(v[1]), float(v[2]), float(v[3]))
                for v in (line.split() for line in f) if v}


def relative_pose(a, b):
    """b in a's frame: (x, y, theta)."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    c, s = math.cos(a[2]), math.sin(a[2])
    return (c * dx + s * dy, -s * dx + c * dy, math.atan2(math.sin(b[2] - a[2]), math.cos(b[2] - a[2])))


def relations_error(poses, relations):
    """Mean translation error of the relations whose two stamps both have a pose in `poses` ({stamp key:
    (x, y, theta)}), computed here independently of the C++ metric; and how many were used."""
    errors = []
    for t1, t2, x, y, _ in relations:
        if t1 in poses and t2 in poses:
            r = relative_pose(poses[t1], poses[t2])
            errors.append(math.hypot(r[0] - x, r[1] - y))
    return (sum(errors) / len(errors) if errors else float("nan")), len(errors)


def simulate(world, seed, scans, prefix="system_", extra=()):
    """Simulates config/worlds/<world>.yaml into a temporary bag (`scans` None: the world's own count);
    returns (bag, truth yaml path, log)."""
    bag = os.path.join(tempfile.mkdtemp(prefix=prefix), world + ".bag")
    count = [] if scans is None else ["--scans", str(scans)]
    rc, out = run(["rosrun", "line_map_eval", "simulate_world",
                   os.path.join(repo_root(), "config", "worlds", world + ".yaml"), bag,
                   "--seed", str(seed), "--no-progress"] + count + list(extra), 120)
    if rc != 0:
        raise RuntimeError("simulate_world failed:\n" + out)
    return bag, bag[:-len(".bag")] + ".truth.yaml", out


def bag_scans(bag, topic="/scan"):
    """(number of scans, stamp of the last scan, seconds between the first and the last scan) of a bag."""
    import rosbag
    stamps = []
    with rosbag.Bag(bag) as b:
        for _, msg, _ in b.read_messages(topics=[topic, topic.lstrip("/")]):
            stamps.append(msg.header.stamp.to_sec())
    if not stamps:
        raise RuntimeError("%s: no %s messages" % (bag, topic))
    return len(stamps), max(stamps), max(stamps) - min(stamps)


def work_limit(bag_seconds, rate, margin=10.0, floor=60.0):
    """A wall-clock limit derived from the work: the bag's duration at the playback rate, times a wide
    margin for a loaded machine, never below `floor` s (start-up of the nodes). Only a limit: the
    waits below end on the awaited event, so an idle machine never waits for it."""
    return max(floor, margin * bag_seconds / float(rate))


def play(bag, rate, timeout=None, topics=None, wait_for_subscribers=True):
    """rosbag play --clock; raises with its output on failure. With wait_for_subscribers the player
    starts only once every played topic has a subscriber (nothing is lost at the start however slowly
    the nodes come up); the timeout defaults to work_limit() of the bag."""
    cmd = ["rosbag", "play", "--clock", "--quiet", "--rate", str(rate), bag]
    if wait_for_subscribers:
        cmd.append("--wait-for-subscribers")
    if topics:
        cmd += ["--topics"] + list(topics)
    if timeout is None:
        timeout = work_limit(bag_scans(bag)[2], rate)
    rc, out = run(cmd, timeout)
    if rc != 0:
        raise RuntimeError("rosbag play failed:\n" + out)


def time_limit_of(script, test_dir):
    """The smallest rostest time-limit [s] of the test/*.test files that run `script`, or None."""
    limits = []
    for name in sorted(os.listdir(test_dir)) if os.path.isdir(test_dir) else []:
        if name.endswith(".test"):
            with open(os.path.join(test_dir, name)) as f:
                for test in re.findall(r"<test\b[^>]*>", f.read()):
                    if re.search(r'\btype="%s"' % re.escape(script), test):
                        limit = re.search(r'\btime-limit="([0-9.]+)"', test)
                        limits.append(float(limit.group(1)) if limit else 60.0)  # rostest's default
    return min(limits) if limits else None


def _test_deadline():
    """When this checker's waits must have ended: its rostest time-limit (counted from the start of the
    test node, about when this module is imported) less a reserve for stopping the nodes. Past the
    time-limit rostest kills the checker, which then leaves no result naming what it awaited."""
    limit = time_limit_of(os.path.basename(sys.argv[0]), os.path.join(repo_root(), "test"))
    if limit is None:
        return None
    return time.time() + limit - max(60.0, 0.1 * limit)


TEST_DEADLINE = _test_deadline()


def within_budget(limit):
    """`limit` [s], shortened to what is left before the test's deadline (at least 1 s)."""
    if TEST_DEADLINE is None:
        return limit
    return max(1.0, min(limit, TEST_DEADLINE - time.time()))


def wait_for(predicate, timeout, step=0.1):
    deadline = time.time() + within_budget(timeout)
    while time.time() < deadline:
        if predicate():
            return True
        time.sleep(step)
    return predicate()


def wait_until(predicate, awaited, arrived, limit, step=0.1, gone=None):
    """Waits for an event; on reaching `limit` s raises AssertionError naming what was awaited and
    what had arrived (`arrived()` describes the state). `gone()`, checked every 2 s, names a dead
    node (or returns None): the wait then fails at once instead of at the limit."""
    t0 = time.time()
    deadline, next_check = t0 + within_budget(limit), t0 + 2.0
    while not predicate():
        now = time.time()
        if gone is not None and now >= next_check:
            next_check = now + 2.0
            dead = gone()
            if dead:
                raise AssertionError("%s while waiting for %s; arrived: %s" % (dead, awaited, arrived()))
        if now >= deadline:
            stacks = dump_stacks()
            raise AssertionError("waited %.0f s (the limit, or what the test's time-limit left) for %s; arrived: %s%s"
                                 % (now - t0, awaited, arrived(), "; thread stacks in " + stacks if stacks else ""))
        time.sleep(step)
    return time.time() - t0


def dump_stacks():
    """Every thread's backtrace of the nodelet managers and project nodes running now (a wait that ran out
    of time: a node stuck in a lock shows where), into a new artefact stacks_N.txt; its path, or None when
    none runs or gdb is missing."""
    import shutil
    if shutil.which("gdb") is None:
        return None
    found = subprocess.run(["pgrep", "-f", "nodelet manager|/devel/lib/line_|/lib/line_map_"],
                           stdout=subprocess.PIPE, universal_newlines=True).stdout.split()
    pids = [p for p in found if p != str(os.getpid())][:4]  # within the reserve left before the time-limit
    if not pids:
        return None
    n = 1
    while os.path.exists(os.path.join(artifact_dir(), "stacks_%d.txt" % n)):
        n += 1
    path = os.path.join(artifact_dir(), "stacks_%d.txt" % n)
    with open(path, "w") as out:
        for pid in pids:
            try:
                with open("/proc/%s/cmdline" % pid) as f:
                    out.write("=== %s: %s\n" % (pid, f.read().replace("\0", " ")))
                out.flush()
                subprocess.run(["gdb", "-p", pid, "-batch", "-nx", "-ex", "thread apply all bt"], stdout=out,
                               stderr=subprocess.STDOUT, timeout=20)
            except (OSError, subprocess.TimeoutExpired) as e:
                out.write("(no backtrace: %s)\n" % e)
    return path


def reported(diagnostics, keys):
    """`keys` of a component_diagnostics dict and how long ago it last reported, for a failed wait's message."""
    age = time.time() - diagnostics[RECEIVED] if RECEIVED in diagnostics else float("inf")
    return ", ".join(["%s: %s" % (k, diagnostics.get(k)) for k in keys] + ["last report %.0f s ago" % age])


def gone_nodes(*topics):
    """A `gone` check for wait_until: names a node publishing one of `topics` that no longer answers
    (a crashed nodelet manager stays registered at the master)."""
    import xmlrpc.client
    import rosgraph

    def check():
        master = rosgraph.Master(rospy.get_name())
        for topic in topics:
            for node in publishers(topic):
                try:
                    xmlrpc.client.ServerProxy(master.lookupNode(node)).getPid(rospy.get_name())
                except (OSError, rosgraph.MasterError, xmlrpc.client.Error):
                    return "node %s (publishing %s) is gone" % (node, topic)
        return None
    return check


# component_diagnostics' key of the wall time its status last came (a node stuck stops reporting).
RECEIVED = "(received at)"


def component_diagnostics(**components):
    """Subscribes to /diagnostics: each keyword names a dict that takes the key-value pairs of the status
    whose name ends with the given text (e.g. slam="laser slam"), its message under "summary" and the wall
    time it came under RECEIVED."""
    from diagnostic_msgs.msg import DiagnosticArray
    found = {name: {} for name in components}

    def take(msg):
        for s in msg.status:
            for name, suffix in components.items():
                if s.name.endswith(suffix):
                    found[name].update({kv.key: kv.value for kv in s.values})
                    found[name]["summary"] = s.message
                    found[name][RECEIVED] = time.time()
    rospy.Subscriber("/diagnostics", DiagnosticArray, take, queue_size=50)
    return found


def stop(proc, timeout):
    """Stops a roslaunch child as Ctrl-C would; killed after `timeout` s."""
    import signal
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def publishers(topic):
    """Nodes publishing `topic`, from the master."""
    import rosgraph
    pubs, _, _ = rosgraph.Master(rospy.get_name()).getSystemState()
    return next((nodes for name, nodes in pubs if name == topic), [])


class Diagnostics:
    """The latest values of each pipeline task's diagnostics (/diagnostics, published by wall timers
    about once a second), by task: "line extraction", "line map merging", "evaluator"."""

    TASKS = ("line extraction", "line map merging", "evaluator")

    def __init__(self):
        from diagnostic_msgs.msg import DiagnosticArray
        self.values = {}
        self.received = {}
        self.sub = rospy.Subscriber("/diagnostics", DiagnosticArray, self._cb, queue_size=50)

    def _cb(self, msg):
        for status in msg.status:
            for task in self.TASKS:
                if status.name.endswith(": " + task) or status.name == task:
                    self.values[task] = {kv.key: kv.value for kv in status.values}
                    self.received[task] = self.received.get(task, 0) + 1

    def counter(self, task, key):
        try:
            return int(float(self.values.get(task, {}).get(key, "-1")))
        except ValueError:
            return -1

    def merged(self):
        """line_segments messages the merger has finished with (keyframe, gated, held for a trajectory,
        dropped, replayed)."""
        if "segment sets handled" in self.values.get("line map merging", {}):
            return self.counter("line map merging", "segment sets handled")
        keys = ("keyframes", "scans below the keyframe gate", "dropped scans", "replayed scans skipped",
                "zero-stamp segments")
        return sum(max(0, self.counter("line map merging", k)) for k in keys)

    def wait_up(self, tasks, limit=60.0):
        """Waits until each task's nodelet is initialised, so its subscriptions exist: the merger and
        the evaluator by their diagnostics (wall timers; made after their subscriptions), the
        extractor by its line_segments publisher at the master (its diagnostics wait for ROS time,
        which stands still before the bag's clock)."""
        def up(task):
            if task == "line extraction":
                return bool(publishers("/line_segments"))
            return task in self.values

        wait_until(lambda: all(up(t) for t in tasks), "the nodelets of %s" % ", ".join(tasks),
                   lambda: "up: %s" % (", ".join(t for t in tasks if up(t)) or "none"), limit)

    def wait_merged(self, segments, last_stamp, limit, since=0):
        """Waits until the pipeline has finished with a played bag: this process has received the
        line_segments of the bag's last scan (among segments.messages[since:]; a full subscriber queue
        drops the oldest message, never the newest), and a merger diagnostics message sent after that
        counts every line_segments message received here as finished with (keyframe, gated, dropped,
        replayed). Should the merger have lost some in its own queue, its counters standing still over
        three diagnostics messages (about 3 s) end the wait instead. Call wait_up() before playing, so
        that the merger and this process count the same messages."""
        state = {"fresh_after": None, "seen": 0, "merged": -1, "same": 0}
        merging = "line map merging"

        def done():
            if state["fresh_after"] is None:
                if not any(abs(m.header.stamp.to_sec() - last_stamp) < 1e-6 for _, m in segments.messages[since:]):
                    return False
                state["fresh_after"] = self.received.get(merging, 0)
            seen = self.received.get(merging, 0)
            if seen <= state["fresh_after"]:
                return False  # the merger's counters from before the last scan reached it
            if seen != state["seen"]:
                state["seen"] = seen
                merged = self.merged()
                state["same"] = state["same"] + 1 if merged == state["merged"] else 0
                state["merged"] = merged
            return state["merged"] >= len(segments.messages) or state["same"] >= 3

        return wait_until(done, "the merger to finish with the bag's last scan (stamp %.3f)" % last_stamp,
                          lambda: "%d line_segments messages here (the last stamped %s); the merger finished "
                          "with %d" % (len(segments.messages), "%.3f" % segments.messages[-1][1].header.stamp.to_sec()
                                       if segments.messages else "-", self.merged()), limit,
                          gone=gone_nodes("/line_segments", "/line_map"))


class Collector:
    """Keeps every message of a topic, tagged with how many optimized_trajectory messages came before."""

    def __init__(self, topic, msg_type, epoch=None):
        self.messages = []
        self._epoch = epoch
        self.sub = rospy.Subscriber(topic, msg_type, self._cb, queue_size=10000)

    def _cb(self, msg):
        self.messages.append((len(self._epoch.messages) if self._epoch else 0, msg))

    def before(self, n=1):
        return [m for e, m in self.messages if e < n]

    def after(self, n=1):
        return [m for e, m in self.messages if e >= n]


# ---- ground-truth wall coverage (independent of the C++ metrics) ----

def rigid_fit(pairs):
    """(theta, tx, ty) mapping the first point of each pair onto the second, least squares (2D closed form)."""
    n = float(len(pairs))
    ax = sum(p[0][0] for p in pairs) / n
    ay = sum(p[0][1] for p in pairs) / n
    bx = sum(p[1][0] for p in pairs) / n
    by = sum(p[1][1] for p in pairs) / n
    cross = sum((p[0][0] - ax) * (p[1][1] - by) - (p[0][1] - ay) * (p[1][0] - bx) for p in pairs)
    dot = sum((p[0][0] - ax) * (p[1][0] - bx) + (p[0][1] - ay) * (p[1][1] - by) for p in pairs)
    theta = math.atan2(cross, dot)
    c, s = math.cos(theta), math.sin(theta)
    return theta, bx - (c * ax - s * ay), by - (s * ax + c * ay)


def moved(segment, fit):
    """The segment (x1, y1, x2, y2) moved by `fit` (theta, tx, ty)."""
    theta, tx, ty = fit
    c, s = math.cos(theta), math.sin(theta)
    x1, y1, x2, y2 = segment
    return (c * x1 - s * y1 + tx, s * x1 + c * y1 + ty, c * x2 - s * y2 + tx, s * x2 + c * y2 + ty)



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

class BagRun:
    """A simulated (or converted) bag through a running pipeline (linemap.launch): plays its sensor
    topics, waits until the merger has finished with the last scan, and drives the loop closure
    itself: it publishes the bag's last trajectory (stamped after every scan, so the adjusted map's
    stamp is its own) and waits for the adjusted line_map and its map_quality. Every wait ends on its
    event; the limit only bounds it, derived from the bag (work_limit)."""

    def __init__(self, bag, rate, evaluator=True):
        from line_map_msgs.msg import LineMap, LineSegmentArray, MapQuality
        self.bag, self.rate, self.evaluator = bag, rate, evaluator
        self.scans, self.last_stamp, span = bag_scans(bag)
        self.limit = work_limit(span, rate)
        self.diag = Diagnostics()
        self.segments = Collector("line_segments", LineSegmentArray)
        self.maps = Collector("line_map", LineMap)
        self.qualities = Collector("map_quality", MapQuality)
        self._pub = None

    def play(self):
        """Plays the sensor topics; returns the map once the merger has finished with the bag."""
        self.diag.wait_up(Diagnostics.TASKS if self.evaluator else Diagnostics.TASKS[:2], self.limit)
        play(self.bag, self.rate, topics=SENSOR_TOPICS)
        self.diag.wait_merged(self.segments, self.last_stamp, self.limit)
        wait_until(lambda: self.maps.messages, "a line_map from the %d scans of the bag" % self.scans,
                   lambda: "no line_map; %d line_segments messages, the merger finished with %d" % (
                       len(self.segments.messages), self.diag.merged()), self.limit)
        line_map = self.maps.messages[-1][1]
        if self.evaluator:
            self.quality_of(line_map)  # the evaluator holds this map: ~evaluate scores it
        return line_map

    def close_loop(self, trajectory=None):
        """Publishes the trajectory (default: the bag's last); returns the adjusted map."""
        if trajectory is None:
            trajectory = bag_trajectories(self.bag)[-1]
        trajectory.header.stamp = rospy.Time.from_sec(self.last_stamp + 0.5)
        n = len(self.maps.messages)
        self._pub = publish_trajectory(trajectory)
        line_map = wait_for_new_map(self.maps, n, "the line_map adjusted to the optimized_trajectory", self.limit)
        if self.evaluator:
            self.quality_of(line_map)
        return line_map

    def quality_of(self, line_map):
        return wait_for_quality_of(self.qualities, line_map, "the map_quality of the line_map stamped %.3f"
                                   % line_map.header.stamp.to_sec(), self.limit)


SENSOR_TOPICS = ("/scan", "/tf", "/tf_static")


def bag_trajectories(bag):
    """The optimized_trajectory messages of a bag, in order."""
    import rosbag
    with rosbag.Bag(bag) as b:
        return [m for _, m, _ in b.read_messages(topics=["/optimized_trajectory", "optimized_trajectory"])]


def evaluate(given_map=None, timeout=60.0):
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


def wait_for_new_map(maps, count, what, limit=60.0):
    """Waits for a line_map beyond the first `count` messages (the merger publishes one per keyframe,
    trajectory and load_map); returns it. Call it once the merger has finished with the scans
    (Diagnostics.wait_merged), so that the new map is the answer to what was sent."""
    wait_until(lambda: len(maps.messages) > count, what,
               lambda: "%d line_map messages, none new" % len(maps.messages), limit, gone=gone_nodes("/line_map"))
    return maps.messages[-1][1]


def wait_for_quality_of(qualities, line_map, what, limit=60.0):
    """Waits for a map_quality of `line_map` (same stamp) received after it; returns the newest."""
    stamp = line_map.header.stamp

    def of_map():
        return [m for _, m in qualities.messages if m.header.stamp == stamp]

    wait_until(lambda: of_map(), what, lambda: "%d map_quality messages, the last stamped %s (awaited %.3f)" % (
        len(qualities.messages), "%.3f" % qualities.messages[-1][1].header.stamp.to_sec() if qualities.messages
        else "-", stamp.to_sec()), limit, gone=gone_nodes("/line_map", "/map_quality"))
    return of_map()[-1]


def publish_trajectory(path):
    """Publishes a trajectory latched, so a subscriber connecting late still receives it (a message at
    the end of a bag may be lost when `rosbag play` exits right after publishing it). Keep the
    returned publisher alive until the answer arrived."""
    pub = rospy.Publisher("optimized_trajectory", type(path), queue_size=1, latch=True)
    pub.publish(path)
    return pub


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


def session_records(path):
    """The records of a session file read by this independent reader (line_map_merging's
    session_file.hpp gives the layout): [(tag, payload)], each checksum verified with zlib's CRC-32."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:16] == b"LINEMAP SESSION\n", data[:16]
    assert struct.unpack_from("<I", data, 16)[0] == 1
    records, at = [], 20
    while at < len(data):
        tag = data[at:at + 4].decode("ascii")
        size, crc = struct.unpack_from("<QI", data, at + 4)
        payload = data[at + 16:at + 16 + size]
        assert len(payload) == size, "record %s truncated" % tag
        assert zlib.crc32(payload) & 0xffffffff == crc, "record %s: checksum" % tag
        records.append((tag, payload))
        at += 16 + size
    assert records[-1][0] == "END ", [t for t, _ in records]
    return records


def session_keyframes(session):
    """(stamp, x, y) of every keyframe of a session file's KEYF and NODE records."""
    records = dict(session_records(session))
    keyf, node = records["KEYF"], records["NODE"]
    n = struct.unpack_from("<Q", keyf)[0]
    stamps, at = [], 8
    for _ in range(n):
        stamps.append(struct.unpack_from("<d", keyf, at)[0])
        at += 8 + 8 + 24 + 8
        m = struct.unpack_from("<Q", keyf, at)[0]
        at += 8 + 16 * m
        j = struct.unpack_from("<Q", keyf, at)[0]
        at += 8 + 32 * j
    poses = [struct.unpack_from("<3d", node, 8 + 24 * k) for k in range(n)]
    map_keyframes = int(re.search(rb"keyframe_count: (\d+)", records["LMAP"]).group(1))
    return [(t, p[0], p[1]) for t, p in zip(stamps, poses)], map_keyframes


def save_batch_session(test, recording, work, session):
    """Maps RECORDING offline (linemap_batch --slam --merger cae, its output in WORK/batch) and saves the session to
    SESSION; fails TEST unless the batch exits 0. Returns session_keyframes(SESSION)."""
    rc, log = run(["rosrun", "line_map_eval", "linemap_batch", recording, "--slam", "--merger", "cae",
                   "--no-figures", "--no-progress", "--out", os.path.join(work, "batch"),
                   "--save-session", session], 600)
    test.assertEqual(rc, 0, log)
    return session_keyframes(session)


# The merger's wait for a segment set's transform in the session pipelines [s]: it waits as long as the SLAM
# takes to pose the scan. The SLAM searches the saved map scan by scan, then catches up with the scans queued
# meanwhile. The merger's queue waits while the SLAM's tf moves on, but drops a set once it has not for
# tf_timeout: a loop closure's optimisation on a busy machine may take longer than the default 0.5 s, and
# these tests are about sessions, not about a loaded machine (a CI run once left the merger without any new
# keyframe, before the queue followed the tf).
SESSION_TF_TIMEOUT = 3600.0


def start_session_pipeline(name, session, search_scans=400, by_service=False):
    """linemap.launch slam:=true session:=SESSION session_search_scans:=SEARCH_SCANS, its output in the artefact
    NAME_roslaunch.log; BY_SERVICE: the pipeline starts without a session, which is then given through the SLAM's
    ~load_session (start SEARCH). The merger waits SESSION_TF_TIMEOUT for a scan's transform, so what it maps
    does not depend on how fast the machine is. Returns (the roslaunch process, the SLAM's and the merger's
    diagnostics as they arrive, the SLAM's session key) once both report; the caller stops the process."""
    diagnostics = component_diagnostics(slam="laser slam", merging="line map merging")
    slam, merging = diagnostics["slam"], diagnostics["merging"]
    launch_log = open(os.path.join(artifact_dir(), name + "_roslaunch.log"), "w")
    args = {"slam": "true", "session_search_scans": str(search_scans), "evaluate": "false", "output": "log"}
    if not by_service:
        args["session"] = session
    launch = os.path.join(tempfile.mkdtemp(prefix=name + "_launch_"), "pipeline.launch")
    with open(launch, "w") as f:
        f.write('<launch>\n  <include file="%s">\n%s  </include>\n'
                '  <param name="line_map_merging/tf_timeout" value="%s"/>\n</launch>\n' % (
                    os.path.join(repo_root(), "launch", "linemap.launch"),
                    "".join('    <arg name="%s" value="%s"/>\n' % kv for kv in sorted(args.items())),
                    SESSION_TF_TIMEOUT))
    pipeline = subprocess.Popen(["roslaunch", launch], stdout=launch_log, stderr=subprocess.STDOUT,
                                start_new_session=True)
    key = "session " + session
    try:
        if by_service:
            from line_map_msgs.srv import LoadSession, LoadSessionRequest
            rospy.wait_for_service("/slam/load_session", 120.0)
            answer = rospy.ServiceProxy("/slam/load_session", LoadSession)(
                path=session, start=LoadSessionRequest.SEARCH)
            if not answer.success or "looking for the robot" not in answer.message:
                raise AssertionError("~load_session (SEARCH) refused %s: %s" % (session, answer.message))
        wait_until(lambda: key in slam and "keyframes" in merging, "the SLAM's session diagnostics",
                   lambda: "slam %s, merging %s" % (sorted(slam)[:3], bool(merging)), 120.0)
    except BaseException:
        stop(pipeline, 30)
        raise
    return pipeline, slam, merging, key

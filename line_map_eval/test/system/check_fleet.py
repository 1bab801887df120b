#!/usr/bin/python3
"""Rostest checker (test/fleet.test): two robots into one map, live. The simulated office's drive is cut into two
overlapping parts, each a robot of its own (robot1, robot2: its own topics and frames, its odometry from zero),
each running extraction and SLAM on board (launch/robot.launch); one merger off board (launch/fleet.launch).
The second robot sets out while the first is still driving, from where the first passed a little earlier; the
merger knows nothing of where. It must place robot2's map frame in robot1's where the truth puts it (tf
map -> robot2/map against the two SLAMs' trajectories fitted to the true poses), and the one map must cover the
office's seen walls as one robot's map does."""
import copy
import math
import os
import sys
import tempfile
import unittest

import rosbag
import rospy
import rostest
import tf2_ros
from line_map_msgs.msg import LineMap, MapQuality
from nav_msgs.msg import Path

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import linemap_testing as lt  # noqa: E402

RATE = 1.0
ROBOTS = ("robot1", "robot2")


def compose(a, b):
    """a * b of (x, y, theta) poses."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2])


def inverse(a):
    c, s = math.cos(a[2]), math.sin(a[2])
    return (-c * a[0] - s * a[1], s * a[0] - c * a[1], -a[2])


def yaw(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def prefixed(frame, robot):
    return robot + "/" + frame.lstrip("/")


def fleet_bag(bag, out):
    """The simulated bag as two robots: robot1 drives scans [0, 70 %), robot2 scans [45 %, end) with its odometry
    from zero and its clock shifted to set out when robot1 reaches 60 % (the merger's map lags behind a robot by
    what its SLAM has not yet optimised: robot2 sets out where the map already is). Returns (scans of robot1, scans of
    robot2, robot2's time shift [s]). map -> odom is left out: each robot's SLAM publishes its own."""
    with rosbag.Bag(bag) as b:
        stamps = [m.header.stamp.to_sec() for _, m, _ in b.read_messages(topics=["/scan"])]
    n = len(stamps)
    first_end, second_start = stamps[7 * n // 10 - 1], stamps[45 * n // 100]
    shift = stamps[6 * n // 10] - second_start
    counts = [0, 0]
    zero = None
    with rosbag.Bag(out, "w") as o, rosbag.Bag(bag) as b:
        for topic, msg, t, header in b.read_messages(topics=["/scan", "/tf", "/tf_static"],
                                                     return_connection_header=True):
            name = topic.lstrip("/")
            if name == "tf_static":  # one message for both robots: the topic is latched
                mounted = copy.deepcopy(msg)
                mounted.transforms = []
                for robot in ROBOTS:
                    for x in copy.deepcopy(msg.transforms):
                        x.header.frame_id = prefixed(x.header.frame_id, robot)
                        x.child_frame_id = prefixed(x.child_frame_id, robot)
                        mounted.transforms.append(x)
                o.write(topic, mounted, t, connection_header=header)
                continue
            stamp = msg.header.stamp.to_sec() if name == "scan" else msg.transforms[0].header.stamp.to_sec()
            if name == "tf":
                msg.transforms = [x for x in msg.transforms if x.header.frame_id.lstrip("/") == "odom"]
                if not msg.transforms:
                    continue
            if stamp <= first_end:
                write(o, topic, name, msg, "robot1", 0.0, None)
                counts[0] += name == "scan"
            if stamp >= second_start:
                if name == "tf" and zero is None:
                    p = msg.transforms[0].transform
                    zero = inverse((p.translation.x, p.translation.y, yaw(p.rotation)))
                if name == "tf" or zero is not None:
                    write(o, topic, name, msg, "robot2", shift, zero)
                    counts[1] += name == "scan"
    return counts[0], counts[1], shift


def write(bag, topic, name, msg, robot, shift, zero):
    if name == "scan":
        scan = copy.deepcopy(msg)
        scan.header.frame_id = prefixed(msg.header.frame_id, robot)
        scan.header.stamp = rospy.Time.from_sec(msg.header.stamp.to_sec() + shift)
        bag.write("/%s/scan" % robot, scan, scan.header.stamp)
        return
    out = type(msg)()
    for x in msg.transforms:
        y = type(x)()
        y.header.frame_id = prefixed(x.header.frame_id, robot)
        y.child_frame_id = prefixed(x.child_frame_id, robot)
        y.header.stamp = rospy.Time.from_sec(x.header.stamp.to_sec() + shift)
        p = (x.transform.translation.x, x.transform.translation.y, yaw(x.transform.rotation))
        if zero is not None:
            p = compose(zero, p)
        y.transform.translation.x, y.transform.translation.y = p[0], p[1]
        y.transform.rotation.z, y.transform.rotation.w = math.sin(0.5 * p[2]), math.cos(0.5 * p[2])
        out.transforms.append(y)
    bag.write(topic, out, out.transforms[0].header.stamp)


class CheckFleet(unittest.TestCase):
    def test_two_robots_make_one_map(self):
        sim, truth_file, _ = lt.simulate("office", 1, None, prefix="fleet_")
        bag = os.path.join(tempfile.mkdtemp(prefix="fleet_"), "fleet.bag")
        scans1, scans2, shift = fleet_bag(sim, bag)
        true_pose = {}
        for p in lt.bag_trajectories(sim)[-1].poses:
            true_pose[round(p.header.stamp.to_sec(), 6)] = (p.pose.position.x, p.pose.position.y)
        paths = {}
        for robot in ROBOTS:
            rospy.Subscriber("/%s/optimized_trajectory" % robot, Path,
                             lambda m, r=robot: paths.__setitem__(r, m), queue_size=10)
        maps = []
        rospy.Subscriber("/line_map", LineMap, lambda m: maps.append(m), queue_size=10)
        qualities = lt.Collector("/map_quality", MapQuality)
        merging = lt.component_diagnostics(merging="line map merging")["merging"]
        tf = tf2_ros.Buffer()
        tf2_ros.TransformListener(tf)
        lt.wait_until(lambda: "keyframes" in merging, "the merger's diagnostics", lambda: "none yet", 120.0)
        limit = lt.work_limit(lt.bag_scans(bag, "/robot1/scan")[2] + lt.bag_scans(bag, "/robot2/scan")[2], RATE)
        lt.play(bag, RATE, timeout=limit)
        lt.wait_until(lambda: "placed after" in merging.get("robot 1", "")
                      and int(merging.get("segment sets handled", "0")) >= scans1 + scans2 - 10 and maps
                      and all(r in paths for r in ROBOTS),
                      "robot2 placed and every segment set handled",
                      lambda: "robot 1: %s; %s of %d segment sets handled; %d maps" % (
                          merging.get("robot 1"), merging.get("segment sets handled"), scans1 + scans2, len(maps)),
                      limit, gone=lt.gone_nodes("/line_map"))
        fits = {}
        for robot in ROBOTS:
            back = shift if robot == "robot2" else 0.0
            pairs = [((p.pose.position.x, p.pose.position.y),
                      true_pose[round(p.header.stamp.to_sec() - back, 6)]) for p in paths[robot].poses
                     if round(p.header.stamp.to_sec() - back, 6) in true_pose]
            self.assertGreater(len(pairs), 20, "%s's keyframes matched to true poses by stamp" % robot)
            fits[robot] = lt.rigid_fit(pairs)
        # (theta, tx, ty) -> (x, y, theta): robot2/map in robot1/map, as the two fits to the truth have it.
        world1 = (fits["robot1"][1], fits["robot1"][2], fits["robot1"][0])
        world2 = (fits["robot2"][1], fits["robot2"][2], fits["robot2"][0])
        expected = compose(inverse(world1), world2)
        t = tf.lookup_transform("map", "robot2/map", rospy.Time(0), rospy.Duration(5.0)).transform
        placed = (t.translation.x, t.translation.y, yaw(t.rotation))
        error = compose(inverse(expected), placed)
        live = [lt.moved(s, fits["robot1"]) for s in lt.map_segments(maps[-1])]
        quality = lt.wait_for_quality_of(qualities, maps[-1], "the last map", limit)
        # The faces an extractor can map (as test/office_pipeline.test counts them), within 0.1 m: the map is
        # registered by the SLAM, not the truth.
        walls = lt.seen_walls(lt.load_truth(truth_file), 1.0, 10, 0.4, 0.3)
        total = sum(sum(b - a for a, b in iv) for _, _, iv in walls)
        covered = sum(lt.coverage(w, iv, live, 0.1) * sum(b - a for a, b in iv) for _, w, iv in walls) / total
        summary = "fleet: %s; placement %.3f m, %.4f rad from the truth; %d map segments cover %.1f %% of the " \
                  "seen faces, q %.2f %%; merger: %s keyframes, %s dropped scans, %s scans of unplaced robots forgotten" % (
                      merging.get("robot 1"), math.hypot(error[0], error[1]), error[2], len(live), 100.0 * covered,
                      quality.quality,
                      merging.get("keyframes"), merging.get("dropped scans"),
                      merging.get("scans of unplaced robots forgotten"))
        print(summary)
        with open(os.path.join(lt.artifact_dir(), "fleet.txt"), "w") as f:
            f.write(summary + "\n")
        self.assertLess(math.hypot(error[0], error[1]), 0.2)
        self.assertLess(abs(math.remainder(error[2], 2.0 * math.pi)), 0.05)
        self.assertGreater(covered, 0.85)
        self.assertGreater(quality.quality, 85.0)


if __name__ == "__main__":
    rospy.init_node("check_fleet")
    rostest.rosrun("line_map_eval", "check_fleet", CheckFleet)

#!/usr/bin/python3
"""The install space of a catkin_make build directory, used as a deployed robot would: installs the
build into an empty directory (its cmake_install.cmake with DESTDIR, as packaging does: nothing is
rebuilt; catkin bakes the configured prefix into its install rules, and the installed setup.bash
finds its own place), sources the installed setup.bash in an environment holding nothing of the repository or
the devel space, and checks that every package resolves to the prefix, that `rospack plugins` lists
every nodelet plugin description there, that the launch files resolve with their config files
(`roslaunch --files`, `--dump-params`), that the tools run (`rosrun line_map_eval <tool> --help`),
and that every nodelet class loads into a manager (own master) from the prefix's libraries, the
shipped parameters loaded first. Writes one JUnit testcase per check.
  check_install.py --build BUILD_DIR/build -o result.xml [--keep DIR]
The install (copies, a few seconds) and the checks take about half a minute."""
import argparse
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import traceback
import xml.etree.ElementTree as ET
import xmlrpc.client

PACKAGES = ["line_map_msgs", "line_extraction", "line_map_merging", "line_map_eval"]
PLUGIN_PACKAGES = ["line_extraction", "line_map_merging", "line_map_eval"]
TOOLS = ["linemap_batch", "linemap_relations", "linemap_export", "carmen_to_bag", "simulate_world"]
# Launch arguments without a default.
LAUNCH_ARGS = {"replay.launch": ["bag:=/nonexistent.bag"], "robot.launch": ["robot:=robot1"]}
# Parameter files loaded into each nodelet's namespace before it loads (as linemap.launch does).
NODELET_CONFIG = {"line_extraction/LineExtractionNodelet": "line_extraction.yaml",
                  "line_map_merging/LineMapMergingNodelet": "line_map_merging.yaml",
                  "line_map_merging/SlamNodelet": "slam.yaml",
                  "line_map_eval/LineMapEvalNodelet": "line_map_eval.yaml"}
# Bound of each wait for a process or service: a loaded machine is slow, a broken install fails fast.
LIMIT = 120.0


class Checks:
    """The testcases of the run, each passed or failed with a message."""

    def __init__(self):
        self.cases = []

    def add(self, name, error=None, output=""):
        self.cases.append((name, error, output))
        print("%s: %s" % (name, "FAILED: " + error if error else "ok"), flush=True)
        if error and output:
            print("  | " + output.strip().replace("\n", "\n  | "), flush=True)
        return error is None

    def write(self, path, seconds):
        suite = ET.Element("testsuite", name="install_space", tests=str(len(self.cases)),
                           failures=str(sum(1 for c in self.cases if c[1])), errors="0", time="%.1f" % seconds)
        for name, error, output in self.cases:
            case = ET.SubElement(suite, "testcase", classname="install_space.InstallSpace", name=name)
            if error:
                failure = ET.SubElement(case, "failure", message=error, type="AssertionError")
                failure.text = output
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        ET.ElementTree(suite).write(path, encoding="utf-8", xml_declaration=True)

    def failed(self):
        return any(c[1] for c in self.cases)


def run(cmd, env, timeout=LIMIT):
    """(exit code, stdout + stderr) of a command in `env`, in its HOME: away from the repository, whose
    config/ the tools would find from the working directory."""
    try:
        p = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=timeout,
                           universal_newlines=True, cwd=env.get("HOME"))
        return p.returncode, p.stdout
    except subprocess.TimeoutExpired as e:
        return -1, "timed out after %.0f s: %s\n%s" % (timeout, " ".join(cmd), e.stdout or "")


def install_environment(prefix, home):
    """The environment of `source PREFIX/setup.bash` started from nothing but the system's PATH."""
    base = {"PATH": "/usr/bin:/bin:/usr/sbin:/sbin", "HOME": home, "ROS_HOME": home,
            "ROS_LOG_DIR": os.path.join(home, "log"), "LANG": "C.UTF-8"}
    # A sanitizer build (SANITIZE=1) loads its nodelets into the uninstrumented manager: scripts/test.sh's
    # options let it.
    base.update({k: v for k, v in os.environ.items() if k in ("ASAN_OPTIONS", "UBSAN_OPTIONS")})
    out = subprocess.run(["bash", "-c", 'source "$0/setup.bash" && env -0', prefix], env=base,
                         stdout=subprocess.PIPE, check=True).stdout.decode()
    return dict(entry.split("=", 1) for entry in out.split("\0") if "=" in entry)


def free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def wait_for(what, predicate, process=None):
    """Polls `predicate` until it holds; None or the reason it did not."""
    deadline = time.time() + LIMIT
    while time.time() < deadline:
        if predicate():
            return None
        if process is not None and process.poll() is not None:
            return "%s: the process exited with %d" % (what, process.returncode)
        time.sleep(0.1)
    return "%s: not within %.0f s" % (what, LIMIT)


def check_paths(checks, env, prefix, forbidden):
    """Every search path of the environment lies in the prefix or outside the repository and build."""
    bad = []
    for var in ["ROS_PACKAGE_PATH", "LD_LIBRARY_PATH", "CMAKE_PREFIX_PATH", "PYTHONPATH", "PKG_CONFIG_PATH"]:
        for entry in filter(None, env.get(var, "").split(":")):
            real = os.path.realpath(entry)
            if not real.startswith(prefix) and any(real.startswith(f) for f in forbidden):
                bad.append("%s holds %s" % (var, entry))
    checks.add("environment_is_the_install_space_alone",
               "the sourced install space reaches the build or source tree" if bad else None, "\n".join(bad))


def check_scripts_drop_the_devel_space(checks, repository, build):
    """The workspace scripts (scripts/env.sh) start from the caller's environment without the repository's
    own paths: a shell that sourced the devel space (the README's step) must not configure the build with it,
    or catkin bakes it into the install space (what check_paths would then find)."""
    devel = os.path.join(os.path.dirname(build), "devel")
    polluted = {"PATH": "/usr/bin:/bin", "HOME": os.environ.get("HOME", "/tmp"),
                "CMAKE_PREFIX_PATH": devel + ":/opt/elsewhere",
                "ROS_PACKAGE_PATH": repository + ":/opt/elsewhere/share",
                "LD_LIBRARY_PATH": os.path.join(devel, "lib"), "PYTHONPATH": "/opt/python:" + devel}
    if os.path.dirname(build).startswith(repository):
        polluted["BUILD_DIR"] = os.path.dirname(build)
    script = 'source "$0/scripts/env.sh" && for v in CMAKE_PREFIX_PATH ROS_PACKAGE_PATH LD_LIBRARY_PATH ' \
             'PYTHONPATH; do echo "$v=${!v-unset}"; done'
    out = subprocess.run(["bash", "-c", script, repository], env=polluted, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, universal_newlines=True).stdout
    got = dict(line.split("=", 1) for line in out.splitlines() if "=" in line)
    expected = {"CMAKE_PREFIX_PATH": "/opt/elsewhere", "ROS_PACKAGE_PATH": "/opt/elsewhere/share",
                "LD_LIBRARY_PATH": "unset", "PYTHONPATH": "/opt/python"}
    checks.add("scripts_drop_the_devel_space", None if got == expected else
               "scripts/env.sh kept the repository's paths: %r, expected %r" % (got, expected), out)


def plugin_classes(xml):
    """(class name, library file name) of a nodelet plugin description."""
    return [(c.get("name"), os.path.basename(library.get("path")) + ".so")
            for library in ET.parse(xml).getroot().iter("library") for c in library.iter("class")]


def check_packages_and_plugins(checks, env, prefix, repository):
    """The classes the repository's plugin descriptions declare (every one must load)."""
    for pkg in PACKAGES:
        rc, out = run(["rospack", "find", pkg], env)
        where = out.strip()
        expected = os.path.join(prefix, "share", pkg)
        checks.add("package_%s" % pkg, None if rc == 0 and where == expected else
                   "rospack find %s gives %r, expected %s" % (pkg, where, expected), out)
    rc, out = run(["rospack", "plugins", "--attrib=plugin", "nodelet"], env)
    listed = dict(line.split(None, 1) for line in out.splitlines() if len(line.split(None, 1)) == 2)
    classes = []
    for pkg in PLUGIN_PACKAGES:
        declared = plugin_classes(os.path.join(repository, pkg, "nodelet_plugins.xml"))
        classes += declared
        xml = os.path.join(prefix, "share", pkg, "nodelet_plugins.xml")
        if listed.get(pkg, "").strip() != xml or not os.path.isfile(xml):
            checks.add("plugins_%s" % pkg, "rospack plugins --attrib=plugin nodelet lists %r for %s, expected %s "
                       "(%s)" % (listed.get(pkg), pkg, xml, "present" if os.path.isfile(xml) else "not installed"),
                       out)
            continue
        missing = sorted({p for p in (os.path.join(prefix, "lib", library) for _, library in declared)
                          if not os.path.isfile(p)})
        error = "installed description differs from the source's" if plugin_classes(xml) != declared else None
        checks.add("plugins_%s" % pkg, "libraries not installed: " + ", ".join(missing) if missing else error)
    return classes


def check_launch_files(checks, env, prefix):
    launch_dir = os.path.join(prefix, "share", "line_map_eval", "launch")
    names = sorted(f for f in os.listdir(launch_dir) if f.endswith(".launch")) if os.path.isdir(launch_dir) else []
    if "linemap.launch" not in names:
        checks.add("launch_files", "no linemap.launch in %s (found %s)" % (launch_dir, names))
        return
    for name in names:
        args = LAUNCH_ARGS.get(name, [])
        rc, out = run(["roslaunch", "--files", "line_map_eval", name] + args, env)
        files = out.split()
        error = None
        if rc != 0 or not files:
            error = "roslaunch --files line_map_eval %s failed (%d)" % (name, rc)
        elif any(not f.startswith(prefix) for f in files):
            error = "roslaunch --files line_map_eval %s resolves outside the prefix" % name
        else:
            # The rosparam files load (config/ beside launch/); linemap.launch's include slam.yaml's.
            extra = ["slam:=true"] if name == "linemap.launch" else []
            rc, params = run(["roslaunch", "--dump-params", "line_map_eval", name] + extra + args, env)
            if rc != 0 or (extra and ("/line_map_merging/fusion/max_angle" not in params or "/slam/" not in params)):
                error = "roslaunch --dump-params line_map_eval %s %s fails or lacks the shipped parameters" % (
                    name, " ".join(extra))
                out = params
        checks.add("launch_%s" % name.replace(".", "_"), error, out)
    rviz = os.path.join(prefix, "share", "line_map_eval", "rviz", "linemap.rviz")
    checks.add("rviz_config", None if os.path.isfile(rviz) else "%s not installed" % rviz)


def check_tools(checks, env, prefix, home):
    for tool in TOOLS:
        rc, out = run(["rosrun", "line_map_eval", tool, "--help"], env)
        checks.add("tool_%s" % tool, None if rc == 0 and "usage" in out.lower() else
                   "rosrun line_map_eval %s --help exits %d" % (tool, rc), out)
    # linemap_batch finds the shipped defaults from its own place (no --config-dir, no repository), then
    # fails on the missing dataset alone: exit code 1 (an error of the run, toolMain's code), the message
    # naming the dataset. A parse error (2), a crash (negative: a signal) or a run that somehow succeeds
    # (0) fails this check, as do the warnings of a missing config.
    rc, out = run(["rosrun", "line_map_eval", "linemap_batch", "/nonexistent.bag", "--out",
                   os.path.join(home, "batch")], env)
    if "no config directory found" in out or "not found; its defaults" in out:
        error = "linemap_batch runs without the shipped config files"
    elif rc != 1 or "/nonexistent.bag" not in out:
        error = "linemap_batch on a missing dataset exits %d (expected 1, naming the dataset)" % rc
    else:
        error = None
    checks.add("tool_linemap_batch_finds_config", error, out)


def check_nodelets(checks, env, prefix, classes, home):
    port = free_port()
    env = dict(env, ROS_MASTER_URI="http://localhost:%d" % port)
    log = open(os.path.join(home, "processes.log"), "w")
    master = subprocess.Popen(["rosmaster", "--core", "-p", str(port)], env=env, stdout=log, stderr=log, cwd=home)
    manager = None
    try:
        error = wait_for("the master", lambda: run(["rosparam", "list"], env, 10)[0] == 0, master)
        if error:
            return checks.add("nodelets_manager", error)
        config = os.path.join(prefix, "share", "line_map_eval", "config")
        for cls, _ in classes:
            name = "/" + cls.replace("/", "_")
            if cls in NODELET_CONFIG:
                rc, out = run(["rosparam", "load", os.path.join(config, NODELET_CONFIG[cls]), name], env)
                if rc != 0:
                    return checks.add("nodelets_config", "rosparam load of %s failed" % NODELET_CONFIG[cls], out)
        manager = subprocess.Popen(["rosrun", "nodelet", "nodelet", "manager", "__name:=install_manager"],
                                   env=env, stdout=log, stderr=log, cwd=home)
        error = wait_for("the manager's load_nodelet service",
                         lambda: run(["rosservice", "find", "nodelet/NodeletLoad"], env, 10)[1].strip() ==
                         "/install_manager/load_nodelet", manager)
        if error:
            return checks.add("nodelets_manager", error)
        for cls, library in classes:
            name = "/" + cls.replace("/", "_")
            request = "{name: '%s', type: '%s', remap_source_args: [], remap_target_args: [], my_argv: [], " \
                      "bond_id: ''}" % (name, cls)
            rc, out = run(["rosservice", "call", "/install_manager/load_nodelet", request], env)
            checks.add("nodelet_%s" % cls.replace("/", "_"), None if rc == 0 and re.search(r"success:\s*True", out)
                       else "the manager did not load %s" % cls, out)
        # The libraries the manager mapped are the prefix's (not a devel space's found elsewhere).
        pid = xmlrpc.client.ServerProxy(lookup_node(env, "/install_manager")).getPid("/check")[2]
        with open("/proc/%d/maps" % pid) as f:
            mapped = {line.split()[-1] for line in f if ".so" in line}
        for cls, library in classes:
            paths = sorted(p for p in mapped if os.path.basename(p) == library)
            checks.add("nodelet_%s_from_prefix" % cls.replace("/", "_"),
                       None if paths and all(p.startswith(prefix) for p in paths) else
                       "%s mapped from %s, expected %s/lib" % (library, paths, prefix))
    finally:
        for p in (manager, master):
            if p is not None and p.poll() is None:
                p.terminate()
                try:
                    p.wait(20)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()
        log.close()


def configured_prefix(build):
    with open(os.path.join(build, "CMakeCache.txt")) as f:
        for line in f:
            if line.startswith("CMAKE_INSTALL_PREFIX:"):
                return os.path.normpath(line.split("=", 1)[1].strip())
    raise RuntimeError("no CMAKE_INSTALL_PREFIX in %s/CMakeCache.txt" % build)


def lookup_node(env, node):
    master = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
    return master.lookupNode("/check", node)[2]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", required=True, help="the catkin_make build directory (cmake_install.cmake)")
    parser.add_argument("-o", "--output-file", required=True)
    parser.add_argument("--keep", help="install here and keep it (default: a temporary directory, removed)")
    args = parser.parse_args()
    args.build = os.path.realpath(args.build)
    start = time.time()
    checks = Checks()
    root = os.path.realpath(args.keep) if args.keep else tempfile.mkdtemp(prefix="linemap_install_")
    destdir, home = os.path.join(root, "destdir"), os.path.join(root, "home")
    shutil.rmtree(destdir, ignore_errors=True)
    os.makedirs(home, exist_ok=True)
    try:
        prefix = destdir + configured_prefix(args.build)
        rc, out = run(["cmake", "-P", os.path.join(args.build, "cmake_install.cmake")],
                      dict(os.environ, DESTDIR=destdir), 600)
        if not checks.add("install", "installing %s failed (%d)" % (args.build, rc) if rc != 0 else None, out):
            pass
        else:
            env = install_environment(prefix, home)
            repository = os.path.realpath(os.path.join(os.path.dirname(__file__), "..", ".."))
            check_paths(checks, env, prefix, [repository, os.path.realpath(os.path.join(args.build, ".."))])
            check_scripts_drop_the_devel_space(checks, repository, args.build)
            classes = check_packages_and_plugins(checks, env, prefix, repository)
            check_launch_files(checks, env, prefix)
            check_tools(checks, env, prefix, home)
            check_nodelets(checks, env, prefix, classes, home)
    except Exception as e:  # a check that broke is a failure, reported as one
        checks.add("checker", "%s: %s" % (type(e).__name__, e), traceback.format_exc())
    finally:
        checks.write(args.output_file, time.time() - start)
        if not args.keep:
            shutil.rmtree(root, ignore_errors=True)
    print("%d checks, %d failed, %.0f s" % (len(checks.cases), sum(1 for c in checks.cases if c[1]),
                                              time.time() - start))
    return 1 if checks.failed() else 0


if __name__ == "__main__":
    sys.exit(main())

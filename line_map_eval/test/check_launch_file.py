#!/usr/bin/python3
"""Checks a launch file with roslaunch's own checker (roslaunch.rlutil.check_roslaunch, the routine
behind roslaunch_add_file_check) and writes a JUnit result. roslaunch-check itself insists that
the file lies inside a package; the suite's launch files live at the repository root (launch/)."""
import argparse
import os
import sys

import roslaunch.rlutil
import rosunit.junitxml


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("launch_file")
    parser.add_argument("-o", "--output-file", required=True)
    parser.add_argument("-i", "--ignore-unset-args", action="store_true",
                        help="do not require a default for every <arg>")
    args = parser.parse_args()
    error = roslaunch.rlutil.check_roslaunch(args.launch_file, ignore_unset_args=args.ignore_unset_args)
    name = os.path.basename(args.launch_file).replace(".", "_")
    os.makedirs(os.path.dirname(os.path.abspath(args.output_file)), exist_ok=True)
    with open(args.output_file, "wb") as f:
        if error:
            f.write(rosunit.junitxml.test_failure_junit_xml(
                name, "roslaunch check [%s] failed" % args.launch_file, stdout=error,
                class_name="roslaunch.RoslaunchCheck", testcase_name=name))
        else:
            f.write(rosunit.junitxml.test_success_junit_xml(
                name, class_name="roslaunch.RoslaunchCheck", testcase_name=name))
    if error:
        print("FAILURE: %s" % error, file=sys.stderr)
        return 1
    print("passed: %s" % args.launch_file)
    return 0


if __name__ == "__main__":
    sys.exit(main())

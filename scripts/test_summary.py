#!/usr/bin/env python3
"""Sums the JUnit result files of a catkin test run; prints the failures and a
final `N passed, N failed[, N skipped]` line; exits 1 on any failure or no test."""
import pathlib
import sys
import xml.etree.ElementTree as ET


def main(root):
    passed = failed = skipped = 0
    failures = []
    files = sorted(pathlib.Path(root).rglob("*.xml")) if pathlib.Path(root).exists() else []
    for path in files:
        try:
            tree = ET.parse(path)
        except ET.ParseError as err:
            failed += 1
            failures.append(f"{path.name}: unreadable result file ({err})")
            continue
        for case in tree.getroot().iter("testcase"):
            name = f"{path.parent.name}/{case.get('classname', '')}.{case.get('name', '')}"
            if case.find("failure") is not None or case.find("error") is not None:
                failed += 1
                node = case.find("failure") if case.find("failure") is not None else case.find("error")
                message = (node.get("message") or node.text or "").strip().splitlines()
                failures.append(f"{name}: {message[0] if message else 'failed'}")
            elif case.find("skipped") is not None or case.get("status") == "notrun":
                skipped += 1
            else:
                passed += 1
    for line in failures:
        print(f"FAILED {line}")
    summary = f"{passed} passed, {failed} failed"
    if skipped:
        summary += f", {skipped} skipped"
    print(summary)
    return 1 if failed or passed == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else ".build/build/test_results"))

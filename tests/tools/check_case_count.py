#!/usr/bin/env python3
"""Every Catch2 test case is a ctest test (issue 14, kind 8).

catch_discover_tests registers one ctest test per case name; a name ctest cannot pass back to Catch2
(one with ';', for instance) would be split into tests that match nothing. This compares, for each
test executable, the cases Catch2 lists with the ctest tests that run it, and fails naming the
difference. Usage: check_case_count.py BUILD_DIR
"""
import json
import os
import subprocess
import sys

build = sys.argv[1]
listing = json.loads(subprocess.run(["ctest", "--test-dir", build, "--show-only=json-v1"], check=True,
                                    capture_output=True, text=True).stdout)
registered = {}  # executable -> ctest test names that run one case of it
for test in listing["tests"]:
    command = test.get("command") or []
    if not command or "install_and_examples" == test["name"] or test["name"] == "catch2_case_count":
        continue
    exe = command[0]
    if os.path.basename(exe).startswith("test_") and len(command) > 1:  # one case per test
        registered.setdefault(exe, []).append(test["name"])
failures = []
total = 0
for exe, names in sorted(registered.items()):
    out = subprocess.run([exe, "--list-test-names-only"], capture_output=True, text=True).stdout
    cases = [line for line in out.splitlines() if line.strip()]
    total += len(cases)
    if sorted(cases) != sorted(names):
        missing = sorted(set(cases) - set(names))
        extra = sorted(set(names) - set(cases))
        failures.append(f"{os.path.basename(exe)}: Catch2 lists {len(cases)} cases, ctest runs {len(names)}"
                        f"; not run as listed: {missing[:5]}; ctest names matching no case: {extra[:5]}")
for f in failures:
    print("check_case_count: " + f, file=sys.stderr)
if failures:
    sys.exit(1)
print(f"check_case_count: {total} Catch2 cases in {len(registered)} executables, each a ctest test")

#!/usr/bin/env python3
"""Runs pytest for ctest (tests/python/CMakeLists.txt) and never hides a skip.

    run_pytest.py [pytest arguments]

Exit status 0: pytest passed and skipped nothing. 77 (ctest's SKIP_RETURN_CODE): nothing failed but
pytest is missing or some tests (or all) skipped; one "SKIPPED: ..." line per skipped test says
why. Anything else: a failure (pytest's own status, or 1). Standard library only."""
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

SKIP = 77


def main():
    probe = subprocess.run([sys.executable, "-c", "import pytest"], capture_output=True)
    if probe.returncode != 0:
        print(f"SKIPPED: no pytest for {sys.executable} (Debian: python3-pytest)")
        return SKIP
    with tempfile.TemporaryDirectory(prefix="sesi-pytest-") as tmp:
        junit = os.path.join(tmp, "pytest.xml")
        status = subprocess.run([sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider",
                                 f"--junitxml={junit}", *sys.argv[1:]]).returncode
        if status != 0:  # failures, errors, or no test collected (5)
            print(f"FAILED: pytest exit status {status}")
            return status
        cases = ET.parse(junit).getroot().iter("testcase")
        total, skipped = 0, []
        for case in cases:
            total += 1
            for mark in case.findall("skipped"):
                skipped.append(f"{case.get('classname')}.{case.get('name')}: {mark.get('message')}")
    for line in skipped:
        print(f"SKIPPED: {line}")
    if skipped:
        print(f"SKIPPED: {len(skipped)} of {total} pytest tests ({total - len(skipped)} passed)")
        return SKIP
    return 0


if __name__ == "__main__":
    sys.exit(main())

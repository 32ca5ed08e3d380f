#!/usr/bin/env python3
"""No silent skips (issue #24): the pieces that make a skipped test say so.

    check_skip_reporting.py --cmake CMAKE --work DIR [--source REPO]

- tests/run_pytest.py: a pytest run where everything skipped, or some tests, exits 77 (ctest's
  SKIP_RETURN_CODE) with a "SKIPPED: reason" line per test; all passed: 0; a failure: neither.
- the program's and the sweep's drivers print "SKIPPED: reason" and exit 77 on a Skip.
- tests/check_skips.cmake fails on ctest's JUnit file when a test skipped, naming it and its reason,
  and passes when none did.
- configure with HDF5 hidden: the H5MD test is still registered and reports SKIPPED with the
  reason; with SESI_REQUIRE_ALL_TESTS the same configure fails, naming the test.
Standard library only; exit status 0 passes."""
import argparse
import contextlib
import io
import pathlib
import shutil
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent
SKIP = 77
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)


def run(*args, **kw):
    return subprocess.run([str(a) for a in args], capture_output=True, text=True, **kw)


def check_pytest_wrapper(work):
    bodies = {
        "all_skipped": "import pytest\ndef test_a():\n    pytest.skip('no widget here')\n"
                       "def test_b():\n    pytest.importorskip('sesi_no_such_module')\n",
        "some_skipped": "import pytest\ndef test_a():\n    assert 1 + 1 == 2\n"
                        "def test_b():\n    pytest.skip('no gadget here')\n",
        "none_skipped": "def test_a():\n    assert 1 + 1 == 2\n",
        "one_failing": "import pytest\ndef test_a():\n    assert 1 + 1 == 3\n"
                       "def test_b():\n    pytest.skip('no gadget here')\n",
    }
    results = {}
    for name, body in bodies.items():
        d = work / "pytest" / name
        d.mkdir(parents=True)
        (d / f"test_{name}.py").write_text(body)
        results[name] = run(sys.executable, HERE / "run_pytest.py", d, cwd=d)
    r = results["all_skipped"]
    check(r.returncode == SKIP, f"all skipped: exit {r.returncode}, expected {SKIP}: {r.stdout[-500:]}")
    check("SKIPPED: " in r.stdout and "no widget here" in r.stdout and "sesi_no_such_module" in r.stdout,
          f"all skipped: no SKIPPED lines with both reasons: {r.stdout[-500:]}")
    r = results["some_skipped"]
    check(r.returncode == SKIP and "no gadget here" in r.stdout and "1 of 2 pytest tests" in r.stdout,
          f"some skipped: exit {r.returncode}: {r.stdout[-500:]}")
    r = results["none_skipped"]
    check(r.returncode == 0 and "SKIPPED" not in r.stdout, f"none skipped: exit {r.returncode}: {r.stdout[-500:]}")
    r = results["one_failing"]
    check(r.returncode not in (0, SKIP), f"one failing: exit {r.returncode}: {r.stdout[-500:]}")


def check_drivers(work):
    # The sweep driver without mpiexec: its MPI case skips (before running sesi at all).
    r = run(sys.executable, HERE / "sweep" / "check_sweep.py", "--sesi", "/nonexistent/sesi", "--work", work / "sweep",
            "--case", "sweep_mpi_ranks", "--mpiexec=")
    check(r.returncode == SKIP and "SKIPPED: sesi is built without MPI" in r.stdout,
          f"check_sweep.py sweep_mpi_ranks without MPI: exit {r.returncode}, stdout {r.stdout!r}")
    # The program driver on a case that raises Skip.
    sys.dont_write_bytecode = True
    sys.path.insert(0, str(HERE / "program"))
    import check_program  # noqa: E402

    def needs_a_part(ctx):
        raise check_program.Skip("no frobnicator (Debian: frobnicator-dev)")

    check_program.CASES["needs_a_part"] = needs_a_part
    argv, sys.argv = sys.argv, ["check_program.py", "--sesi", "/nonexistent/sesi", "--work", str(work / "program"),
                                "--case", "needs_a_part"]
    out = io.StringIO()
    try:
        with contextlib.redirect_stdout(out):
            status = check_program.main()
    finally:
        sys.argv = argv
    check(status == SKIP and "SKIPPED: no frobnicator (Debian: frobnicator-dev)" in out.getvalue(),
          f"check_program.py on a Skip: exit {status}, stdout {out.getvalue()!r}")


def check_junit_check(cmake, work):
    ctest = pathlib.Path(cmake).with_name("ctest")
    for name, skipping in [("with-skip", True), ("without-skip", False)]:
        src, build = work / "junit" / name, work / "junit" / f"{name}-build"
        src.mkdir(parents=True)
        (src / "CMakeLists.txt").write_text(
            "cmake_minimum_required(VERSION 3.20)\nproject(skips NONE)\nenable_testing()\n"
            "add_test(NAME runs COMMAND sh -c \"echo ran\")\n" +
            ("add_test(NAME lacks_part COMMAND sh -c \"echo 'SKIPPED: no thingamajig'; exit 77\")\n"
             "set_tests_properties(lacks_part PROPERTIES SKIP_RETURN_CODE 77)\n" if skipping else ""))
        r = run(cmake, "-S", src, "-B", build)
        check(r.returncode == 0, f"{name}: configure: {r.stderr[-500:]}")
        r = run(ctest, "--test-dir", build, "--output-junit", "junit.xml")
        check(r.returncode == 0, f"{name}: ctest: {r.stdout[-500:]}")
        r = run(cmake, "-D", f"JUNIT={build / 'junit.xml'}", "-P", HERE / "check_skips.cmake")
        if skipping:
            check(r.returncode != 0 and "lacks_part" in r.stderr and "SKIPPED: no thingamajig" in r.stderr
                  and "runs" not in r.stderr.replace("must run", ""),
                  f"check_skips.cmake on a skipped test: exit {r.returncode}, stderr {r.stderr!r}")
        else:
            check(r.returncode == 0, f"check_skips.cmake with no skip: exit {r.returncode}, stderr {r.stderr!r}")


def check_configure(cmake, source, work):
    # The program's tests alone, HDF5 hidden from find_package: the H5MD test stays, SKIPPED.
    common = ["-S", source, "-D", "CMAKE_DISABLE_FIND_PACKAGE_HDF5=ON", "-D", "SESI_TEST_PARTS=program",
              "-D", "SESI_BUILD_EXAMPLES=OFF", "-D", "SESI_BUILD_PYTHON=OFF", "-D", "SESI_INSTALL=OFF",
              "-D", "SESI_SANITIZER_JOB=OFF", "-D", "SESI_BUILD_BENCHMARKS=OFF"]
    build = work / "configure-no-hdf5"
    r = run(cmake, "-B", build, *common, "-D", "SESI_REQUIRE_ALL_TESTS=OFF")
    check(r.returncode == 0, f"configure without HDF5: {r.stderr[-800:]}")
    ctest = pathlib.Path(cmake).with_name("ctest")
    r = run(ctest, "--test-dir", build, "-R", "^program_h5md_trajectory$", "--output-junit", "junit.xml")
    check("***Skipped" in r.stdout, f"program_h5md_trajectory without HDF5 is not reported skipped: {r.stdout!r}")
    junit = (build / "junit.xml").read_text() if (build / "junit.xml").exists() else ""
    check("SKIPPED: the program is built without HDF5" in junit,
          f"program_h5md_trajectory: no SKIPPED reason in its output: {junit[-800:]!r}")
    r = run(cmake, "-B", work / "configure-no-hdf5-required", *common, "-D", "SESI_REQUIRE_ALL_TESTS=ON")
    check(r.returncode != 0 and "program_h5md_trajectory cannot run" in r.stderr,
          f"configure without HDF5 under SESI_REQUIRE_ALL_TESTS: exit {r.returncode}, stderr {r.stderr[-800:]!r}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cmake", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--source", default=str(HERE.parent))
    a = ap.parse_args()
    work = pathlib.Path(a.work)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    check_pytest_wrapper(work)
    check_drivers(work)
    check_junit_check(a.cmake, work)
    check_configure(a.cmake, a.source, work)
    print(f"{len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

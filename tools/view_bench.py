#!/usr/bin/env python3
"""How fast `sesi view`'s page opens (issue #28's target: a 10^4-body, 200-frame run drawn in
headless Chromium in under 3 s). A benchmark, not a test.

    python3 tools/view_bench.py [--sesi build/src/sesi] [--chromium chromium] [--work sesi-out/view-bench]
        [--sizes 10000x200,100000x100] [--format csv|h5md] [--repeats 3]

For each size N x F: a Lennard-Jones liquid on S^2 (tools/lattice_scene.py: a Fibonacci lattice at
density 0.5, sesi2, dt = 0.002, output every step, F - 1 steps), run by `sesi run`; then `sesi view`
writes the page (timed: the writer's wall time, and the page's size); then headless Chromium opens
it (as the tests do, in an empty network namespace where `unshare -n` works), --repeats times each:
  first draw      the page's own state.first_draw_ms (performance.now() when the first frame was
                  drawn, counted from the navigation's start), read with --dump-dom
  screenshot      the wall time of `chromium --screenshot` from launch to exit: start-up, loading and
                  parsing the page, the first draw and the PNG; the target's measure
  dump-dom        the wall time of `chromium --dump-dom`, which also prints the DOM after load to a pipe
  redraw, step    the page's own timing (URL bench=20: state.bench): a redraw of the frame shown
                  (projection on the CPU, buffers, drawing, gl.finish()) and a step to the next frame
                  (decoding it too), each averaged over 20; in SwiftShader's software WebGL here, so
                  the drawing part is the CPU's, slower than any GPU's
Medians of the launches.
"""
import argparse
import json
import pathlib
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent


def chromium_command(chromium, profile, url, isolate, what):
    command = ["unshare", "-n"] if isolate else []
    return command + [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                      "--disable-background-networking", "--disable-component-update", "--disable-sync",
                      "--enable-unsafe-swiftshader", f"--user-data-dir={profile}", "--force-device-scale-factor=1",
                      "--window-size=1280,800", what, url]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sesi", default=str(ROOT / "build" / "src" / "sesi"))
    ap.add_argument("--chromium", default=shutil.which("chromium") or shutil.which("chromium-browser") or "chromium")
    ap.add_argument("--work", default="sesi-out/view-bench")
    ap.add_argument("--sizes", default="10000x200,100000x100")
    ap.add_argument("--format", choices=["csv", "h5md"], default="csv")
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    work = pathlib.Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    isolate = subprocess.run(["unshare", "-n", "true"], capture_output=True).returncode == 0
    rows = []
    for size in a.sizes.split(","):
        n, frames = (int(v) for v in size.lower().split("x"))
        name = f"lj-s2-{n}x{frames}"
        scene = work / f"{name}.toml"
        dt = 0.002
        subprocess.run([sys.executable, str(ROOT / "tools" / "lattice_scene.py"), str(n), str(scene), "--dt", str(dt),
                        "--t-end", repr(dt * (frames - 1)), "--output-every", "1"], check=True)
        run = work / name
        start = time.perf_counter()
        subprocess.run([a.sesi, "run", str(scene), "--out", str(run), "--quiet", "--trajectory-format", a.format],
                       check=True)
        run_seconds = time.perf_counter() - start
        start = time.perf_counter()
        subprocess.run([a.sesi, "view", str(run), "--quiet", "--max-frames", str(frames)], check=True)
        write_seconds = time.perf_counter() - start
        page = run / "view.html"
        size_mb = page.stat().st_size / 1e6
        walls, shots, draws, redraws, steps = [], [], [], [], []
        for _ in range(a.repeats):
            for what, query in ((f"--screenshot={(work / 'shot.png').resolve()}", ""), ("--dump-dom", ""),
                                ("--dump-dom", "?bench=20")):
                profile = tempfile.mkdtemp(prefix="chromium-")
                try:
                    start = time.perf_counter()
                    r = subprocess.run(chromium_command(a.chromium, profile, page.resolve().as_uri() + query, isolate,
                                                        what), capture_output=True, text=True, timeout=600)
                    if not query:
                        (walls if what == "--dump-dom" else shots).append(time.perf_counter() - start)
                finally:
                    shutil.rmtree(profile, ignore_errors=True)
                if what != "--dump-dom":
                    continue
                m = re.search(r'<script[^>]*id="sesi-state"[^>]*>(.*?)</script>', r.stdout, re.S)
                state = json.loads(m.group(1)) if m else {}
                if not state.get("ready"):
                    sys.exit(f"view_bench: the page of {name} drew nothing: {state.get('messages')} "
                             f"{state.get('errors')}")
                if query:
                    redraws.append(state["bench"]["redraw_ms"])
                    steps.append(state["bench"]["step_ms"])
                else:
                    draws.append(state["first_draw_ms"] / 1000)
        rows.append((n, frames, run_seconds, write_seconds, size_mb, statistics.median(draws), statistics.median(shots),
                     statistics.median(walls), statistics.median(redraws), statistics.median(steps), state["renderer"]))
    print(f"view_bench: headless Chromium ({'empty network namespace' if isolate else 'network as it is'}), "
          f"median of {a.repeats} launches; trajectory {a.format}")
    print("| bodies | frames | sesi run (s) | sesi view (s) | page (MB) | first draw (s) | screenshot (s) "
          "| dump-dom (s) | redraw (ms) | step (ms) | renderer |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for n, frames, run_s, write_s, mb, draw, shot, wall, redraw, step, renderer in rows:
        print(f"| {n} | {frames} | {run_s:.1f} | {write_s:.2f} | {mb:.1f} | {draw:.2f} | {shot:.2f} | {wall:.2f} "
              f"| {redraw:.1f} | {step:.1f} | {renderer} |")
    target = [r for r in rows if r[0] == 10000 and r[1] == 200]
    if target:
        verdict = "met" if target[0][6] < 3 else "NOT met"
        print(f"target (issue #28): 10^4 x 200 opened and drawn in under 3 s: screenshot from launch "
              f"{target[0][6]:.2f} s (first draw {target[0][5]:.2f} s after navigation): {verdict}")


if __name__ == "__main__":
    main()

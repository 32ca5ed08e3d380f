#!/usr/bin/env python3
"""H5MD trajectories of `sesi run` (tests/program/CMakeLists.txt; needs h5py).

    check_h5md.py --sesi PATH --source REPO --work DIR

Runs one scene twice, with --trajectory-format csv and h5md, checks the H5MD 1.1 structure of
trajectory.h5 and that every number in it equals trajectory.csv (and the energies of
diagnostics.csv) exactly: both hold the same doubles, the CSV in round-trip form. Likewise a run
on an E^2 periodic box (box edges, boundary "periodic", the image counts) and one on the genus-2
surface (its attributes, unwrapped points and words). Then checks
that an h5md run replaces an earlier output directory as a whole (no trajectory.csv left).
Exit status 0 passes, anything else fails.
"""
import argparse
import json
import pathlib
import shutil
import subprocess
import sys

import h5py
import numpy as np

SCENE = "sphere-pole-crossing.toml"
ARGS = ["--t-end", "30", "--output-every", "7", "--quiet"]


class Failure(Exception):
    pass


def check(condition, message):
    if not condition:
        raise Failure(message)


def run(sesi, *args):
    result = subprocess.run([sesi, *map(str, args)], capture_output=True, text=True, timeout=300,
                            stdin=subprocess.DEVNULL)
    check(result.returncode == 0 and result.stderr == "",
          f"sesi {' '.join(map(str, args))}: exit status {result.returncode}, stderr {result.stderr!r}")


def read_csv(path):
    lines = pathlib.Path(path).read_text().splitlines()
    return lines[0].split(","), [[float(v) for v in line.split(",")] for line in lines[1:]]


def text(value):
    """A fixed-length string attribute, which h5py returns as bytes."""
    return value.decode() if isinstance(value, (bytes, np.bytes_)) else str(value)


def check_file(h5_path, csv_dir, summary):
    header, rows = read_csv(csv_dir / "trajectory.csv")
    _, diagnostics = read_csv(csv_dir / "diagnostics.csv")
    space = summary["space"]
    dim = space["dim"]
    ambient = dim if space["kind"] == "euclidean" else dim + 1
    n = summary["bodies"]
    frames = len(rows)
    check(len(header) == 1 + n * (2 * dim + ambient), f"CSV header {header}")

    with h5py.File(h5_path, "r") as f:
        # H5MD 1.1 metadata.
        check(list(f["h5md"].attrs["version"]) == [1, 1], f"h5md version {f['h5md'].attrs['version']}")
        check(text(f["h5md/author"].attrs["name"]) == "sesi", "h5md/author name")
        check(text(f["h5md/creator"].attrs["name"]) == "sesi", "h5md/creator name")
        check(text(f["h5md/creator"].attrs["version"]) != "", "h5md/creator version")
        box = f["particles/all/box"]
        check(int(box.attrs["dimension"]) == ambient, f"box dimension {box.attrs['dimension']}")
        check([text(b) for b in box.attrs["boundary"]] == ["none"] * ambient, f"box boundary {box.attrs['boundary']}")
        check(text(f["parameters"].attrs["space"]) == space["kind"], "parameters/space")

        # Shapes, types, and the time axis shared by hard links.
        position = f["particles/all/position"]
        step, time = position["step"], position["time"]
        check(step.shape == (frames,) and step.dtype.kind == "i", f"step {step.shape} {step.dtype}")
        check(time.shape == (frames,) and time.dtype == np.float64, f"time {time.shape} {time.dtype}")
        check(position["value"].shape == (frames, n, ambient), f"position {position['value'].shape}")
        for name, shape in [("particles/all/chart_position", (frames, n, dim)),
                            ("particles/all/chart_momentum", (frames, n, dim)),
                            ("observables/energy", (frames,))]:
            element = f[name]
            check(element["value"].shape == shape and element["value"].dtype == np.float64,
                  f"{name}/value {element['value'].shape} {element['value'].dtype}, expected {shape}")
            check(element["step"].id == step.id and element["time"].id == time.id,
                  f"{name}: step and time are not the position's")
        check(position["value"].chunks is not None and position["value"].compression == "gzip"
              and position["value"].shuffle, "position/value is not chunked, shuffled and deflated")
        check(position["value"].maxshape[0] is None, "position/value is not extensible")
        check(f["particles/all/mass"].shape == (n,), f"mass {f['particles/all/mass'].shape}")

        # The numbers: exactly those of the CSV run.
        t = time[()]
        check(t.tolist() == [r[0] for r in rows], "time differs from trajectory.csv's t")
        every, steps = summary["output_every"], summary["steps"]
        expected_steps = list(range(0, steps, every)) + [steps]
        check(step[()].tolist() == expected_steps, f"steps {step[()].tolist()}, expected {expected_steps}")
        x, q, p = position["value"][()], f["particles/all/chart_position/value"][()], \
            f["particles/all/chart_momentum/value"][()]
        per_body = 2 * dim + ambient
        for k, row in enumerate(rows):
            for b in range(n):
                base = 1 + b * per_body
                check(q[k, b].tolist() == row[base:base + dim], f"q differs at frame {k}, body {b + 1}")
                check(p[k, b].tolist() == row[base + dim:base + 2 * dim], f"p differs at frame {k}, body {b + 1}")
                check(x[k, b].tolist() == row[base + 2 * dim:base + per_body], f"x differs at frame {k}, body {b + 1}")
        energy = f["observables/energy/value"][()]
        check(energy.tolist() == [r[1] for r in diagnostics], "energy differs from diagnostics.csv")
        check(x[-1].tolist() == [body["x"] for body in summary["final_state"]["bodies"]],
              "last frame differs from the summary's final state")
    return frames


# Runs on a topology (issue #26): an E^2 box of free bodies, and the Bolza surface (genus 2).
BOX_SCENE = """name = "h5md-box"
[space]
kind = "euclidean"
dim = 2
box = [3.0, 2.0]
[[bodies]]
mass = 1.0
q = [1.0, 1.0]
p = [1.3, 0.7]
[[bodies]]
mass = 2.0
q = [0.2, 1.9]
p = [-1.8, 4.2]
[integrator]
dt = 0.01
t_end = 10.0
output_every = 20
"""

SURFACE_SCENE = """name = "h5md-surface"
[space]
kind = "hyperbolic"
dim = 2
radius = 2.0
genus = 2
[[bodies]]
mass = 1.0
q = [0.3, 0.4]
p = [1.1, 0.6]
[[bodies]]
mass = 1.0
q = [0.5, 2.0]
p = [-0.4, 1.3]
[integrator]
dt = 0.01
t_end = 12.0
output_every = 20
"""


def check_topology_file(h5_path, csv_dir, summary):
    """trajectory.h5 of a run on a topology against trajectory.csv: the box (or surface) and the
    image record, number for number and word for word."""
    rows = (csv_dir / "trajectory.csv").read_text().splitlines()
    header, lines = rows[0].split(","), [line.split(",") for line in rows[1:]]
    space = summary["space"]
    dim, n = space["dim"], summary["bodies"]
    box = "box" in space
    ambient = dim if box else dim + 1
    per_body = 2 * dim + ambient + (dim if box else ambient + 1)
    check(len(header) == 1 + n * per_body, f"CSV header {header}")
    with h5py.File(h5_path, "r") as f:
        group = f["particles/all/box"]
        check(int(group.attrs["dimension"]) == ambient, f"box dimension {group.attrs['dimension']}")
        boundary = [text(b) for b in group.attrs["boundary"]]
        step = f["particles/all/position/step"]
        x = f["particles/all/position/value"][()]
        check(x.shape == (len(lines), n, ambient), f"position {x.shape}")
        for k, row in enumerate(lines):
            for b in range(n):
                base = 1 + b * per_body + 2 * dim
                check(x[k, b].tolist() == [float(v) for v in row[base:base + ambient]], f"x differs at frame {k}, body {b + 1}")
        if box:
            check(boundary == ["periodic"] * dim, f"box boundary {boundary}")
            check(group["edges"][()].tolist() == space["box"], f"box edges {group['edges'][()]}")
            image = f["particles/all/image"]
            check(image["value"].dtype.kind == "i" and image["value"].shape == (len(lines), n, dim),
                  f"image {image['value'].shape} {image['value'].dtype}")
            check(image["step"].id == step.id, "image: step is not the position's")
            values = image["value"][()]
            for k, row in enumerate(lines):
                for b in range(n):
                    base = 1 + b * per_body + 2 * dim + ambient
                    check(values[k, b].tolist() == [int(c) for c in row[base:base + dim]],
                          f"image differs at frame {k}, body {b + 1}")
            check(any(values.ravel()), "no body crossed a side: the image counts were not put to the test")
        else:
            check(boundary == ["none"] * ambient, f"box boundary {boundary}")
            check(text(group.attrs["sesi_topology"]) == "hyperbolic-surface" and int(group.attrs["genus"]) == space["genus"]
                  and float(group.attrs["radius"]) == space["radius"], f"surface attributes {dict(group.attrs)}")
            unwrapped, word = f["particles/all/unwrapped_position"], f["particles/all/word"]
            check(unwrapped["value"].shape == (len(lines), n, ambient) and word["value"].shape == (len(lines), n),
                  f"unwrapped_position {unwrapped['value'].shape}, word {word['value'].shape}")
            check(unwrapped["step"].id == step.id and word["time"].id == f["particles/all/position/time"].id,
                  "unwrapped_position, word: step and time are not the position's")
            u, words = unwrapped["value"][()], word["value"][()]
            for k, row in enumerate(lines):
                for b in range(n):
                    base = 1 + b * per_body + 2 * dim + ambient
                    check(u[k, b].tolist() == [float(v) for v in row[base:base + ambient]],
                          f"unwrapped_position differs at frame {k}, body {b + 1}")
                    w = words[k, b]
                    check((w.decode() if isinstance(w, bytes) else w) == row[base + ambient],
                          f"word differs at frame {k}, body {b + 1}: {w!r} against {row[base + ambient]!r}")
            check(any((w.decode() if isinstance(w, bytes) else w) != "e" for w in words.ravel()),
                  "no body crossed a side: the words were not put to the test")


def check_topologies(sesi, work):
    for name, scene_text in [("box", BOX_SCENE), ("surface", SURFACE_SCENE)]:
        scene = work / f"{name}.toml"
        scene.write_text(scene_text)
        csv_dir, h5_dir = work / f"{name}-csv", work / f"{name}-h5md"
        run(sesi, "run", scene, "--quiet", "--out", csv_dir)
        run(sesi, "run", scene, "--quiet", "--trajectory-format", "h5md", "--out", h5_dir)
        summary = json.loads((h5_dir / "summary.json").read_text())
        check_topology_file(h5_dir / "trajectory.h5", csv_dir, summary)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--sesi", required=True)
    parser.add_argument("--source", required=True, type=pathlib.Path)
    parser.add_argument("--work", required=True, type=pathlib.Path)
    args = parser.parse_args()
    work = args.work
    if work.exists():
        shutil.rmtree(work)
    work.mkdir(parents=True)
    scene = args.source / "examples" / "scenes" / SCENE

    csv_dir, h5_dir = work / "csv", work / "h5md"
    run(args.sesi, "run", scene, *ARGS, "--trajectory-format", "csv", "--out", csv_dir)
    run(args.sesi, "run", scene, *ARGS, "--trajectory-format", "h5md", "--out", h5_dir)
    check(sorted(p.name for p in h5_dir.iterdir()) == ["diagnostics.csv", "sesi-manifest.txt", "summary.json", "trajectory.h5"],
          f"h5md outputs: {sorted(p.name for p in h5_dir.iterdir())}")
    summary = json.loads((h5_dir / "summary.json").read_text())
    csv_summary = json.loads((csv_dir / "summary.json").read_text())
    check(summary["trajectory"] == "trajectory.h5" and csv_summary["trajectory"] == "trajectory.csv",
          "summary.json names the wrong trajectory file")
    check((h5_dir / "diagnostics.csv").read_bytes() == (csv_dir / "diagnostics.csv").read_bytes(),
          "diagnostics.csv depends on the trajectory format")
    frames = check_file(h5_dir / "trajectory.h5", csv_dir, summary)

    # The same run gives the same bytes (no timestamps in the file).
    again = work / "h5md-again"
    run(args.sesi, "run", scene, *ARGS, "--trajectory-format", "h5md", "--out", again)
    check((again / "trajectory.h5").read_bytes() == (h5_dir / "trajectory.h5").read_bytes(),
          "two identical runs wrote different trajectory.h5")

    # An h5md run into a directory holding an earlier CSV run replaces it as a whole, and the
    # scene key works like the option.
    scene_h5 = work / "scene-h5md.toml"
    source = scene.read_text()
    check("[integrator]" in source, f"{SCENE} has no [integrator] table")
    scene_h5.write_text(source.replace("[integrator]", '[integrator]\ntrajectory_format = "h5md"', 1))
    run(args.sesi, "run", scene_h5, *ARGS, "--out", csv_dir)
    names = sorted(p.name for p in csv_dir.iterdir())
    check(names == ["diagnostics.csv", "sesi-manifest.txt", "summary.json", "trajectory.h5"], f"replaced outputs: {names}")
    leftovers = [p.name for p in work.iterdir() if ".sesi-" in p.name]
    check(not leftovers, f"staging directories left behind: {leftovers}")
    check((csv_dir / "trajectory.h5").read_bytes() == (h5_dir / "trajectory.h5").read_bytes(),
          "trajectory_format in the scene and --trajectory-format give different files")
    # ... and a CSV run replaces an h5md run's directory (trajectory.h5 is a sesi output).
    run(args.sesi, "run", scene, *ARGS, "--out", csv_dir)
    names = sorted(p.name for p in csv_dir.iterdir())
    check(names == ["diagnostics.csv", "sesi-manifest.txt", "summary.json", "trajectory.csv"], f"replaced outputs: {names}")
    check_topologies(args.sesi, work)
    print(f"check_h5md.py: {SCENE}, {frames} frames: trajectory.h5 equals trajectory.csv; so do a box's and a "
          "surface's, with their image counts and words")


if __name__ == "__main__":
    try:
        main()
    except Failure as failure:
        print(f"check_h5md.py: FAILED: {failure}", file=sys.stderr)
        sys.exit(1)

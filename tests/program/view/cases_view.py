# `sesi view DIR` (src/cli/view_command.cpp, src/view, docs/view.md): the page it writes (its meta
# JSON and frame lines, decoded here against the run's trajectory), the manifest, thinning, an
# unfinished run, bad input (one line, exit 2, nothing written) and --serve. What the page draws
# is tested in a real browser by tests/view.
import base64
import re
import select
import socket
import struct
import urllib.error
import urllib.request


def view_sphere_scene(bodies=12, t_end=1.0, output_every=10):
    """A small Lennard-Jones gas on S^2 (a Fibonacci spiral, tangent velocities), masses 1 to 2."""
    radius = math.sqrt(bodies / (4 * math.pi * 0.3))
    golden = math.pi * (3 - math.sqrt(5))
    lines = ['name = "view-lj"', "[space]", 'kind = "sphere"', "dim = 2", f"radius = {radius!r}"]
    for k in range(bodies):
        z = 1 - 2 * (k + 0.5) / bodies
        rho = math.sqrt(1 - z * z)
        x = [radius * rho * math.cos(k * golden), radius * rho * math.sin(k * golden), radius * z]
        norm = math.hypot(x[0], x[1]) or 1.0
        s = 0.5 + 0.5 * math.sin(k)
        v = [-s * x[1] / norm, s * x[0] / norm, 0.0]
        lines += ["[[bodies]]", f"mass = {1.0 + (k % 3) * 0.5!r}", f"x = {x!r}", f"v = {v!r}"]
    lines += ["[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 0.8", "cutoff = 2.0",
              "[[potential]]", 'kind = "lennard-jones"', "epsilon = 0.5", "sigma = 1.0", "cutoff = 2.5",
              "[integrator]", 'method = "sesi2"', "dt = 0.005", f"t_end = {t_end!r}",
              f"output_every = {output_every}"]
    return "\n".join(lines) + "\n"


# Bodies in a periodic box [0, 2)^2, fast enough to cross its faces several times; a short-ranged
# Lennard-Jones term (they never come within its cutoff) so that the run reduces them into the
# domain at every row.
VIEW_BOX_SCENE = """name = "view-box"
[space]
kind = "euclidean"
dim = 2
box = [2.0, 2.0]
[[bodies]]
mass = 1.0
x = [0.5, 0.5]
v = [3.0, 0.7]
[[bodies]]
mass = 2.0
x = [1.5, 1.0]
v = [-0.4, 2.5]
[[bodies]]
mass = 1.0
x = [1.0, 1.9]
v = [0.0, 0.0]
[[potential]]
kind = "lennard-jones"
epsilon = 1.0
sigma = 0.01
cutoff = 0.025
[integrator]
method = "sesi2"
dt = 0.01
t_end = 2.0
output_every = 5
"""


def view_run(ctx, name, text, *args):
    out = ctx.work / name
    scene = ctx.write(f"{name}.toml", text)
    expect_ok(ctx.run("run", scene, "--out", out, "-q", *args), f"sesi run {name}")
    return out


def view_page_parts(path):
    """(meta, frame lines) of a page: the JSON and the text between the markers' script tags."""
    html = pathlib.Path(path).read_text()
    # The markers as the template holds them (the scripts may name them too, to test for them).
    for marker in ("<style>/*SESI_CSS*/</style>", 'id="sesi-meta">/*SESI_META*/</script>',
                   'id="sesi-frames">/*SESI_FRAMES*/</script>', "<script>/*SESI_JS*/</script>"):
        check(marker not in html, f"{path}: the template's marker {marker} was not replaced")
    meta = re.search(r'<script type="application/json" id="sesi-meta">(.*?)</script>', html, re.S)
    frames = re.search(r'<script type="text/plain" id="sesi-frames">(.*?)</script>', html, re.S)
    check(meta is not None and frames is not None, f"{path}: no #sesi-meta or #sesi-frames element")
    text = frames.group(1)
    return json.loads(meta.group(1)), (text.split("\n") if text else [])


def view_decode(line, meta):
    """One frame line: positions (per body, ambient numbers), speeds or None, jumps or None."""
    parts = line.split(",")
    n, a = meta["bodies"], meta["ambient"]
    f = meta["frames"]
    check(len(parts) == 1 + f["speed"] + f["jumps"], f"a frame line has {len(parts)} parts")
    kind = "d" if f["encoding"] == "f64" else "f"
    raw = base64.b64decode(parts[0], validate=True)
    check(len(raw) == n * a * struct.calcsize(kind), f"positions of {len(raw)} bytes for {n} x {a}")
    flat = struct.unpack(f"<{n * a}{kind}", raw)
    x = [flat[b * a:(b + 1) * a] for b in range(n)]
    speeds = jumps = None
    k = 1
    if f["speed"]:
        speeds = struct.unpack(f"<{n}f", base64.b64decode(parts[k], validate=True))
        k += 1
    if f["jumps"]:
        jumps = list(base64.b64decode(parts[k], validate=True))
        check(len(jumps) == n and set(jumps) <= {0, 1}, f"jump flags {jumps}")
    return x, speeds, jumps


def view_trajectory(out, a):
    """Rows of trajectory.csv as (t, [per body x], [per body extra columns as text])."""
    lines = (pathlib.Path(out) / "trajectory.csv").read_text().splitlines()
    header = lines[0].split(",")
    rows = []
    for line in lines[1:]:
        cells = line.split(",")
        bodies = {}
        for name, cell in zip(header[1:], cells[1:]):
            body, column = name.split("_")
            bodies.setdefault(int(body[1:]) - 1, {})[column] = cell
        xs = [[float(bodies[b][f"x{i}"]) for i in range(1, a + 1)] for b in range(len(bodies))]
        rows.append((float(cells[0]), xs, bodies))
    return rows


@case
def view_packed_page(ctx):
    out = view_run(ctx, "view-lj", view_sphere_scene())
    result = ctx.run("view", out)
    expect_ok(result, "sesi view")
    page = out / "view.html"
    check(str(page) in result.stdout and "file://" in result.stdout, f"report: {result.stdout!r}")
    check("view.html" in (out / "sesi-manifest.txt").read_text().splitlines(), "view.html is not in the manifest")
    meta, lines = view_page_parts(page)
    check(meta["format"] == "sesi-view 1" and meta["title"] == "view-lj", f"format, title: {meta['format']}, {meta['title']}")
    space = meta["space"]
    run = summary(out)
    check(space["kind"] == "sphere" and space["dim"] == 2 and space["radius"] == run["space"]["radius"],
          f"space {space}")
    check(space["box"] is None and space["genus"] is None, f"space {space}")
    check(meta["ambient"] == 3 and meta["bodies"] == 12 and meta["masses"] == run["masses"], "ambient, bodies, masses")
    check(meta["complete"] is True and meta["status"] == "", "a finished run shown as unfinished")
    # Half the smallest Lennard-Jones sigma of the scene (0.8 and 1.0).
    check(meta["body_radius"] == 0.4, f"body_radius {meta['body_radius']}")
    rows = view_trajectory(out, 3)
    frames = meta["frames"]
    check(frames["count"] == len(rows) == 21 and len(lines) == 21, f"{frames['count']} frames, {len(lines)} lines")
    check(frames["t"] == [r[0] for r in rows], "the frames' times are not the trajectory's")
    check(frames["encoding"] == "f32" and frames["speed"] and not frames["jumps"] and not frames["stream"],
          f"frames {dict((k, v) for k, v in frames.items() if k != 't')}")
    check(frames["thinned_from"] is None, "thinned though under --max-frames")
    masses = meta["masses"]
    for k in (0, 20):
        x, speeds, _ = view_decode(lines[k], meta)
        for b in range(12):
            for i in range(3):
                exact = rows[k][1][b][i]
                # f32 rounding to nearest: |x - fl(x)| <= |x| 2^-24.
                check(abs(x[b][i] - exact) <= abs(exact) * 2.0 ** -24,
                      f"frame {k} body {b} x{i + 1}: {x[b][i]} vs {exact}")
            check(speeds[b] >= 0.0, f"negative speed {speeds[b]}")
    # The kinetic temperature at t0 from the page's own speeds: sum m |v|^2 / (N n), n = 2. The
    # speeds are f32 (relative 2^-24 each, 2^-23 squared), a sum of positive terms keeps that, and
    # the series is the same sum of doubles: 2^-22 bounds the difference.
    _, speeds, _ = view_decode(lines[0], meta)
    series = {s["name"]: s for s in meta["diagnostics"]["series"]}
    check(set(series) == {"relative energy error", "kinetic temperature"}, f"series {list(series)}")
    temperature = sum(m * s * s for m, s in zip(masses, speeds)) / (12 * 2)
    first = series["kinetic temperature"]
    check(first["t"][0] == 0.0 and abs(first["y"][0] - temperature) <= 2.0 ** -22 * temperature,
          f"kinetic temperature {first['y'][0]} vs {temperature} from the speeds")
    _, diagnostics = read_csv(out / "diagnostics.csv")
    energy = series["relative energy error"]
    check(energy["t"] == [r[0] for r in diagnostics], "energy error times")
    check(energy["y"] == [r[2] / abs(diagnostics[0][1]) for r in diagnostics], "energy error / |E0|")
    # Again: sesi's own view.html is replaced; a run repeated into the directory replaces it too.
    before = page.stat().st_mtime_ns
    expect_ok(ctx.run("view", out, "-q"), "sesi view again")
    check(page.stat().st_mtime_ns >= before and page.is_file(), "view.html not rewritten")
    check(not [p.name for p in out.iterdir() if p.name.startswith(".view.html")], "temporary files left")
    expect_ok(ctx.run("run", ctx.work / "view-lj.toml", "--out", out, "-q"), "sesi run into a viewed directory")
    check(not page.exists(), "a rerun kept the earlier run's view.html")


@case
def view_precision_64(ctx):
    out = view_run(ctx, "view-lj", view_sphere_scene(t_end=0.2))
    expect_ok(ctx.run("view", out, "--precision", "64", "-q"), "sesi view --precision 64")
    meta, lines = view_page_parts(out / "view.html")
    check(meta["frames"]["encoding"] == "f64", f"encoding {meta['frames']['encoding']}")
    rows = view_trajectory(out, 3)
    for k, line in enumerate(lines):
        x, _, _ = view_decode(line, meta)
        # The CSV's %.17g reads back to the same double: equal bit for bit.
        check([list(p) for p in x] == rows[k][1], f"frame {k}: f64 positions differ from the trajectory's")
    # --out FILE elsewhere: written there, DIR and its manifest untouched.
    before = snapshot(out)
    other = ctx.work / "elsewhere.html"
    expect_ok(ctx.run("view", out, "--out", other, "-q"), "sesi view --out")
    check(other.is_file(), "--out FILE not written")
    expect_untouched(out, before)


@case
def view_surface_polygon(ctx):
    out = ctx.work / "bolza"
    expect_ok(ctx.run("run", ctx.scene("bulk-lj-bolza.toml"), "--out", out, "--t-end", "0.3", "--output-every", "20",
                      "-q"), "sesi run bulk-lj-bolza")
    expect_ok(ctx.run("view", out, "-q"), "sesi view of a genus-2 surface")
    meta, lines = view_page_parts(out / "view.html")
    space = meta["space"]
    radius = space["radius"]
    check(space["kind"] == "hyperbolic" and space["genus"] == 2 and space["max_cutoff"] > 0, f"space {space}")
    check(meta["body_radius"] == 0.5, f"body_radius {meta['body_radius']} (sigma 1)")
    polygon = meta["polygon"]
    check(len(polygon["vertices"]) == 8, f"{len(polygon['vertices'])} vertices, expected 4g = 8")
    for v in polygon["vertices"]:
        lorentz = v[0] ** 2 + v[1] ** 2 - v[2] ** 2
        # Each square is at most R^2 cosh^2(circumradius) = R^2 cot^4(pi/8) ~ 34 R^2; a few
        # roundings of that are ~1e-14 R^2, well inside 1e-12 relative.
        check(v[2] > 0 and abs(lorentz + radius ** 2) <= 1e-12 * radius ** 2, f"vertex {v}: <x,x>_L = {lorentz}")
    # The identity first, then the 4g (4g - 2) = 48 tiles sharing a vertex with it.
    check(len(polygon["tiles"]) == 49 and polygon["tiles"][0] == [1, 0, 0, 0, 1, 0, 0, 0, 1], "tiles")
    rows = view_trajectory(out, 3)
    check(meta["frames"]["jumps"] and len(lines) == len(rows), "no jump flags on a surface")
    for k, line in enumerate(lines):
        _, _, jumps = view_decode(line, meta)
        words = [rows[k][2][b]["word"] for b in range(meta["bodies"])]
        previous = [rows[k - 1][2][b]["word"] for b in range(meta["bodies"])] if k else words
        check(jumps == [int(w != p) for w, p in zip(words, previous)], f"frame {k}: jumps differ from word changes")


@case
def view_box_jumps(ctx):
    out = view_run(ctx, "view-box", VIEW_BOX_SCENE)
    expect_ok(ctx.run("view", out, "-q"), "sesi view of a periodic box")
    meta, lines = view_page_parts(out / "view.html")
    check(meta["space"]["box"] == [2.0, 2.0] and meta["ambient"] == 2 and meta["polygon"] is None, "box space")
    check(meta["body_radius"] == 0.005, f"body_radius {meta['body_radius']} (sigma 0.01)")
    rows = view_trajectory(out, 2)
    jumped = 0
    for k, line in enumerate(lines):
        x, _, jumps = view_decode(line, meta)
        counts = [(rows[k][2][b]["n1"], rows[k][2][b]["n2"]) for b in range(3)]
        previous = [(rows[k - 1][2][b]["n1"], rows[k - 1][2][b]["n2"]) for b in range(3)] if k else counts
        check(jumps == [int(c != p) for c, p in zip(counts, previous)], f"frame {k}: jumps {jumps}")
        # In the domain [0, 2), up to f32 rounding (which may round up to 2).
        check(all(0.0 <= c <= 2.0 for p in x for c in p), f"frame {k}: a position outside the box's domain")
        jumped += sum(jumps)
    # Body 1 crosses x = 2 every 2/3 time units: at least twice in t_end = 2.
    check(jumped >= 2 and lines and view_decode(lines[0], meta)[2] == [0, 0, 0], f"{jumped} jumps")


@case
def view_thinning(ctx):
    out = view_run(ctx, "view-lj", view_sphere_scene(t_end=1.0, output_every=10))  # 21 frames
    result = ctx.run("view", out, "--max-frames", "5", "-q")
    check(result.returncode == 0 and "thinned" in result.stderr and result.stderr.count("\n") == 1,
          f"exit {result.returncode}, stderr {result.stderr!r}")
    meta, lines = view_page_parts(out / "view.html")
    rows = view_trajectory(out, 3)
    frames = meta["frames"]
    check(frames["count"] == 5 and len(lines) == 5 and frames["thinned_from"] == 21, f"frames {frames}")
    # Evenly: rows round(i 20 / 4) = 0, 5, 10, 15, 20, the first and last among them.
    check(frames["t"] == [rows[k][0] for k in (0, 5, 10, 15, 20)], f"times {frames['t']}")
    x, _, _ = view_decode(lines[-1], meta)
    check(all(abs(x[b][i] - rows[20][1][b][i]) <= abs(rows[20][1][b][i]) * 2.0 ** -24 for b in range(12)
              for i in range(3)), "the last frame kept is not the trajectory's last")
    # --every and --from/--to choose the frames before thinning.
    expect_ok(ctx.run("view", out, "--from", "0.5", "--every", "2", "-q"), "sesi view --from --every")
    meta, _ = view_page_parts(out / "view.html")
    check(meta["frames"]["t"] == [rows[k][0] for k in (10, 12, 14, 16, 18, 20)], f"times {meta['frames']['t']}")


@case
def view_unfinished_run(ctx):
    failed = ctx.work / "blowup"
    ctx.run("run", ctx.write("blowup.toml", BLOWUP), "--out", failed, "-q")
    check(not summary(failed)["complete"], "the blow-up scene should fail")
    result = ctx.run("view", failed, "-q")
    check(result.returncode == 0, f"exit status {result.returncode}: {result.stderr!r}")
    check("did not finish" in result.stderr and result.stderr.count("\n") == 1, f"stderr {result.stderr!r}")
    meta, lines = view_page_parts(failed / "view.html")
    reason = summary(failed)["stop_reason"]
    check(meta["complete"] is False and meta["status"].startswith(reason), f"complete/status: {meta['status']!r}")
    check(meta["frames"]["count"] == len(lines) >= 1, "no frames of the unfinished run")


@case
def view_bad_input(ctx):
    out = view_run(ctx, "view-lj", view_sphere_scene(t_end=0.2))
    before = snapshot(out)
    empty = ctx.work / "empty"
    empty.mkdir()
    no_trajectory = ctx.work / "no-trajectory"
    no_trajectory.mkdir()
    for name in ("summary.json", "sesi-manifest.txt"):
        (no_trajectory / name).write_bytes((out / name).read_bytes())
    cases = [
        (["view", ctx.work / "missing"], "not a directory"),
        (["view", empty], "no summary.json"),
        (["view", no_trajectory], "trajectory"),
        (["view", out, "--precision", "16"], "--precision"),
        (["view", out, "--max-frames", "0"], "--max-frames"),
        (["view", out, "--every", "0"], "--every"),
        (["view", out, "--from", "5"], "no frame"),
        (["view", out, "--from", "inf"], "--from"),
        (["view", out, "--serve", "--out", ctx.work / "x.html"], "--out"),
        (["view", out, "--out", ctx.work / "no-such-dir" / "x.html"], "--out"),
        (["view"], "DIR"),
    ]
    for args, text in cases:
        expect_input_error(ctx.run(*args), text=text)
        expect_untouched(out, before)
    check(sorted(p.name for p in empty.iterdir()) == [], "something written into an empty directory")
    check(sorted(p.name for p in no_trajectory.iterdir()) == ["sesi-manifest.txt", "summary.json"],
          "something written beside a summary without a trajectory")
    check(not (ctx.work / "x.html").exists(), "--out written on bad input")
    # A view.html that sesi did not write is refused, not replaced.
    (out / "view.html").write_text("mine\n")
    before = snapshot(out)
    expect_input_error(ctx.run("view", out), text="did not write")
    expect_untouched(out, before)


@case
def view_serve(ctx):
    out = view_run(ctx, "view-lj", view_sphere_scene(t_end=0.2))
    expect_ok(ctx.run("view", out, "-q"), "sesi view (the packed page to compare with)")
    _, packed = view_page_parts(out / "view.html")
    before = snapshot(out)
    server = subprocess.Popen([ctx.sesi, "view", str(out), "--serve", "--port", "0"], cwd=ctx.work,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
    try:
        ready, _, _ = select.select([server.stdout], [], [], 60)
        check(ready, "sesi view --serve printed no URL")
        line = server.stdout.readline()
        found = re.fullmatch(r"serving (.*) at (http://127\.0\.0\.1:(\d+)/) \(Ctrl-C to stop\)\n", line)
        check(found is not None, f"first line {line!r}")
        url = found.group(2)
        # A connection that sends nothing (browsers open some ahead of use) holds up no other.
        idle = socket.create_connection(("127.0.0.1", int(found.group(3))), timeout=30)
        # Straight to 127.0.0.1: no proxy from the environment.
        opener = urllib.request.build_opener(urllib.request.ProxyHandler({}))
        page = opener.open(url, timeout=30).read().decode()
        meta = re.search(r'<script type="application/json" id="sesi-meta">(.*?)</script>', page, re.S)
        check(meta is not None and json.loads(meta.group(1))["frames"]["stream"] is True, "the served page is not a stream page")
        frames = re.search(r'<script type="text/plain" id="sesi-frames">(.*?)</script>', page, re.S)
        check(frames is not None and frames.group(1) == "", "the stream page holds frame lines")
        for k in (0, len(packed) - 1):
            body = opener.open(f"{url}frames/{k}", timeout=30).read().decode()
            check(body == packed[k], f"frames/{k} differs from the packed page's line {k}")
        for missing in (f"frames/{len(packed)}", "frames/x", "nothing"):
            try:
                opener.open(url + missing, timeout=30)
                check(False, f"{missing}: expected 404")
            except urllib.error.HTTPError as e:
                check(e.code == 404, f"{missing}: HTTP {e.code}")
        idle.close()
        server.send_signal(signal.SIGINT)
        status = server.wait(timeout=30)
        check(status == 0, f"exit status {status} after SIGINT; stderr {server.stderr.read()!r}")
    finally:
        if server.poll() is None:
            server.kill()
            server.wait()
    expect_untouched(out, before)


@case
def view_far_hyperbolic_f64(ctx):
    # A body 6 radii from the origin of H^2 (R = 1): beyond 5 R the page's positions are f64 (auto).
    # Both velocities are tangent (<x, v>_L = 0) with no time component: Minkowski norm 0.1.
    far = [math.sinh(6.0), 0.0, math.cosh(6.0)]
    text = "\n".join(['name = "view-far"', "[space]", 'kind = "hyperbolic"', "dim = 2", "radius = 1.0",
                      "[[bodies]]", "mass = 1.0", f"x = {[0.0, math.sinh(0.5), math.cosh(0.5)]!r}", "v = [0.1, 0.0, 0.0]",
                      "[[bodies]]", "mass = 1.0", f"x = {far!r}", "v = [0.0, 0.1, 0.0]",
                      "[integrator]", 'method = "sesi2"', "dt = 0.01", "t_end = 0.1", "output_every = 5"]) + "\n"
    out = view_run(ctx, "view-far", text)
    expect_ok(ctx.run("view", out, "-q"), "sesi view of a far body")
    meta, lines = view_page_parts(out / "view.html")
    check(meta["frames"]["encoding"] == "f64" and meta["polygon"] is None, f"encoding {meta['frames']['encoding']}")
    rows = view_trajectory(out, 3)
    x, speeds, _ = view_decode(lines[-1], meta)
    check([list(p) for p in x] == rows[-1][1], "f64 positions differ from the trajectory's")
    # Speeds: the Minkowski norm of the tangent velocity, 0.1 all along (free motion conserves it:
    # the run's relative energy error, checked below 1e-6, bounds the change of |v| by half that,
    # and f32 adds 2^-24 relative). In the last frame the far body's Euclidean |v| would be ~0.22:
    # its time component is 0.1 cosh(6) sinh(0.01) ~ 0.2 (the geodesic x cosh s + u sinh s).
    _, diagnostics = read_csv(out / "diagnostics.csv")
    drift = max(abs(r[2] / diagnostics[0][1]) for r in diagnostics)
    check(drift < 1e-6, f"relative energy error {drift} of free motion")
    for line in lines:
        _, speeds, _ = view_decode(line, meta)
        check(all(abs(s - 0.1) <= 0.1 * (drift / 2 + 2.0 ** -24) + 1e-17 for s in speeds), f"speeds {speeds}")
    expect_ok(ctx.run("view", out, "--precision", "32", "-q"), "sesi view --precision 32")
    meta, _ = view_page_parts(out / "view.html")
    check(meta["frames"]["encoding"] == "f32", "--precision 32 not kept")


@case
def view_h5md_equals_csv(ctx):
    csv_out = view_run(ctx, "view-csv", view_sphere_scene(t_end=0.2))
    h5_out = ctx.work / "view-h5"
    scene = ctx.write("view-h5.toml", view_sphere_scene(t_end=0.2).replace("[integrator]", '[integrator]\ntrajectory_format = "h5md"'))
    result = ctx.run("run", scene, "--out", h5_out, "-q")
    if result.returncode == 2 and "HDF5" in result.stderr:
        return  # a program built without HDF5 refuses h5md (cases in outputs/ check that message)
    expect_ok(result, "sesi run with an H5MD trajectory")
    pages = []
    for out in (csv_out, h5_out):
        expect_ok(ctx.run("view", out, "-q"), f"sesi view {out.name}")
        pages.append(view_page_parts(out / "view.html"))
    # The same doubles in both trajectories: the same frame lines, byte for byte.
    (csv_meta, csv_lines), (h5_meta, h5_lines) = pages
    check(h5_meta["source"]["trajectory"] == "trajectory.h5", f"source {h5_meta['source']}")
    check(csv_lines == h5_lines and csv_meta["frames"] == h5_meta["frames"], "the pages' frames differ")


@case
def view_thermostat_temperature(ctx):
    thermostat = '[thermostat]\nkind = "langevin"\ngamma = 1.0\nseed = 1\ntemperature = 1.0\n[integrator]'
    out = view_run(ctx, "view-langevin", view_sphere_scene(t_end=0.2).replace("[integrator]", thermostat))
    expect_ok(ctx.run("view", out, "-q"), "sesi view of a thermostatted run")
    meta, lines = view_page_parts(out / "view.html")
    header, rows = read_csv(out / "diagnostics.csv")
    series = {s["name"]: s for s in meta["diagnostics"]["series"]}
    column = header.index("kinetic_temperature")
    check(series["kinetic temperature"]["y"] == [r[column] for r in rows], "not the run's kinetic_temperature")
    # The run's definition agrees with the one the page computes for runs without the column:
    # sum m |v|^2 / (N n) from the f32 speeds (2^-22 relative, as in view_packed_page).
    _, speeds, _ = view_decode(lines[0], meta)
    own = sum(m * s * s for m, s in zip(meta["masses"], speeds)) / (12 * 2)
    check(abs(own - rows[0][column]) <= 2.0 ** -22 * own, f"kinetic temperature {own} vs the run's {rows[0][column]}")

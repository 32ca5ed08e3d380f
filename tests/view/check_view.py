#!/usr/bin/env python3
"""Browser tests of `sesi view` (issue #28), one ctest test per case (tests/view/CMakeLists.txt).

    check_view.py --list
    check_view.py --sesi PATH --chromium PATH --source REPO --work DIR --case NAME [--pythonpath DIR]

Each case writes its scene into a fresh work directory, runs it with `sesi run`, writes the page
with `sesi view`, opens it in headless Chromium (under `unshare -n`, an empty network namespace,
where that works) and reads the page's own state (the #sesi-state JSON of docs/view.md, printed
by --dump-dom) and a --screenshot of the same URL. The expected screen positions are computed
here from the run's trajectory.csv with the projections' formulas (Poincare disc and ball,
stereographic, Cayley transform: Cannon, Floyd, Kenyon, Parry, "Hyperbolic geometry" (1997),
sections 7-8; Ratcliffe, Foundations of Hyperbolic Manifolds, 3rd ed., sections 4.5-4.6), never
with the page's code. Standard library only. Exit 0 passes, anything else fails.
"""
import argparse
import html
import json
import math
import os
import pathlib
import re
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
import zlib

HERE = pathlib.Path(__file__).resolve().parent
F32 = 2.0 ** -24  # unit round-off of float32 (the page's f32 frames and its Float32Array of projected points)
SLACK = 1e-9  # px: float64 arithmetic on CSS px of order 1e3 (1e3 x 2^-52 x a few operations ~ 1e-12)


def screen_rounding(x, y):
    """The page keeps screen positions in float32: a relative 2^-24 of each coordinate (CSS px)."""
    return (abs(x) + abs(y)) * F32 + SLACK
WIDTH, HEIGHT = 800, 600  # the browser window, CSS px (device scale factor forced to 1)
CANVAS = "width=640&height=400"  # the viewer's canvas, CSS px (its URL parameters)
CASES = {}


def case(function):
    CASES[function.__name__] = function
    return function


class Failure(Exception):
    pass


def check(condition, message):
    if not condition:
        raise Failure(message)


# ---- running things ----------------------------------------------------------------------------

class Context:
    def __init__(self, args):
        self.sesi = args.sesi
        self.chromium = args.chromium
        self.source = pathlib.Path(args.source)
        self.work = pathlib.Path(args.work)
        self.pythonpath = args.pythonpath
        # An empty network namespace (issue #28: the page must work with no network at all).
        probe = subprocess.run(["unshare", "-n", "true"], capture_output=True)
        self.isolate = probe.returncode == 0 and not args.in_namespace
        if args.in_namespace:
            print("in a network namespace of its own with only the loopback interface up")
        elif not self.isolate:
            print("note: `unshare -n` does not work here (not root?): Chromium runs with the network as it is; "
                  "the page's requests are still checked (state.resources, net::ERR lines)")

    def write(self, name, text):
        path = self.work / name
        path.write_text(text)
        return path

    def sesi_run(self, scene_text, name, expect=0):
        scene = self.write(name + ".toml", scene_text)
        out = self.work / name
        r = subprocess.run([self.sesi, "run", str(scene), "--out", str(out), "--quiet"], capture_output=True,
                           text=True, timeout=120, stdin=subprocess.DEVNULL)
        check(r.returncode == expect, f"sesi run {name}: exit {r.returncode}, expected {expect}: {r.stderr.strip()}")
        return out

    def sesi_view(self, run_dir, *options, expect=0):
        r = subprocess.run([self.sesi, "view", str(run_dir), "--quiet", *options], capture_output=True, text=True,
                           timeout=120, stdin=subprocess.DEVNULL)
        check(r.returncode == expect, f"sesi view {run_dir.name}: exit {r.returncode}: {r.stderr.strip()}")
        page = run_dir / "view.html"
        for i, o in enumerate(options):
            if o == "--out":
                page = pathlib.Path(options[i + 1])
        return page, r

    def browse(self, page, query="", screenshot=False, canvas=True, in_process_iframes=False):
        """Opens file://page?query in headless Chromium; returns (dom or PNG path, stderr). A viewer
        page gets a fixed canvas size (CANVAS), so that --dump-dom and --screenshot, whose windows
        Chromium lays out at different heights, draw the same picture."""
        if canvas:
            query = "&".join(filter(None, [query, CANVAS]))
        url = page.resolve().as_uri() + ("?" + query if query else "")
        profile = tempfile.mkdtemp(prefix="chromium-", dir=self.work)
        command = ["unshare", "-n"] if self.isolate else []
        command += [self.chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                    "--disable-background-networking", "--disable-component-update", "--disable-sync",
                    "--enable-unsafe-swiftshader", f"--user-data-dir={profile}", "--enable-logging=stderr", "--v=0",
                    "--force-device-scale-factor=1", "--hide-scrollbars", f"--window-size={WIDTH},{HEIGHT}"]
        if in_process_iframes:
            # A sandboxed iframe runs in a process of its own by default, and --screenshot then
            # often fires before that process has drawn (seen in about half the launches here);
            # in the parent's process its drawing is part of the page's.
            command.append("--disable-features=IsolateSandboxedIframes")
        png = None
        if screenshot:
            png = self.work / f"shot-{len(list(self.work.glob('shot-*.png')))}.png"
            command.append(f"--screenshot={png}")
        else:
            command.append("--dump-dom")
        command.append(url)
        try:
            r = subprocess.run(command, capture_output=True, text=True, timeout=90, stdin=subprocess.DEVNULL)
        finally:
            shutil.rmtree(profile, ignore_errors=True)
        check(r.returncode == 0, f"chromium exit {r.returncode} on {url}: {r.stderr[-2000:]}")
        expect_clean_log(r.stderr, url)
        if screenshot:
            check(png.exists(), f"chromium wrote no screenshot of {url}")
            return png, r.stderr
        return r.stdout, r.stderr

    def state_when_drawn(self, url, query, wait_s=60):
        """The state of a page that draws when a fetch resolves (the stream page): Chromium driven
        through its DevTools protocol on a pipe (--remote-debugging-pipe: commands on fd 3, replies
        on fd 4, NUL-terminated JSON), reading #sesi-state until the page is no longer loading,
        for at most wait_s (a cap on a wait, not a timed assertion)."""
        url = url + "?" + "&".join(filter(None, [query, CANVAS]))
        profile = tempfile.mkdtemp(prefix="chromium-", dir=self.work)
        to_browser, commands = os.pipe()
        replies, from_browser = os.pipe()
        command = [self.chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                   "--disable-background-networking", "--disable-component-update", "--disable-sync",
                   "--enable-unsafe-swiftshader", f"--user-data-dir={profile}", "--enable-logging=stderr", "--v=0",
                   "--force-device-scale-factor=1", "--hide-scrollbars", f"--window-size={WIDTH},{HEIGHT}",
                   "--remote-debugging-pipe", "about:blank"]
        browser = subprocess.Popen(["sh", "-c", f'exec "$@" 3<&{to_browser} 4>&{from_browser}', "sh", *command],
                                   pass_fds=(to_browser, from_browser), stdin=subprocess.DEVNULL,
                                   stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        os.close(to_browser)
        os.close(from_browser)
        buffer = b""
        ids = iter(range(1, 1 << 30))

        def call(method, session=None, **params):
            nonlocal buffer
            i = next(ids)
            message = {"id": i, "method": method, "params": params}
            if session:
                message["sessionId"] = session
            os.write(commands, json.dumps(message).encode() + b"\0")
            while True:
                while b"\0" not in buffer:
                    chunk = os.read(replies, 1 << 16)
                    check(chunk, "chromium closed its DevTools pipe")
                    buffer += chunk
                text, buffer = buffer.split(b"\0", 1)
                reply = json.loads(text)
                if reply.get("id") == i:
                    check("error" not in reply, f"DevTools {method}: {reply.get('error')}")
                    return reply["result"]

        try:
            target = call("Target.createTarget", url=url)["targetId"]
            session = call("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
            expression = "(document.getElementById('sesi-state') || {}).textContent || ''"
            deadline = time.monotonic() + wait_s
            while True:
                value = call("Runtime.evaluate", session, expression=expression)["result"].get("value", "")
                st = json.loads(value) if value.strip().startswith("{") else {}
                if st.get("ready") or st.get("errors") or time.monotonic() > deadline:
                    break
                time.sleep(0.1)
            call("Browser.close")
        finally:
            os.close(commands)
            os.close(replies)
            try:
                stderr = browser.communicate(timeout=30)[1]
            except subprocess.TimeoutExpired:
                browser.kill()
                stderr = browser.communicate()[1]
            shutil.rmtree(profile, ignore_errors=True)
        expect_clean_log(stderr, url)
        check(st, f"{url}: no #sesi-state JSON")
        return st

    def state(self, page, query=""):
        """The page's state after load (query: URL parameters, with the canvas size added)."""
        dom, _ = self.browse(page, query)
        return parse_state(dom, query)


def expect_clean_log(stderr, url):
    """No console message reporting an error and no failed network request (net::ERR_...)."""
    for line in stderr.splitlines():
        check("net::ERR" not in line, f"{url}: a failed request: {line}")
        if ":INFO:CONSOLE" in line:
            check(not re.search(r"error|uncaught|exception|failed", line, re.I), f"{url}: console: {line}")


def parse_state(dom, query=""):
    m = re.search(r'<script[^>]*id="sesi-state"[^>]*>(.*?)</script>', dom, re.S)
    check(m is not None, f"no #sesi-state element in the page (?{query}): {dom[:300]!r}")
    try:
        return json.loads(m.group(1))
    except json.JSONDecodeError as e:
        raise Failure(f"#sesi-state is not JSON (?{query}): {e}: {m.group(1)[:300]!r}")


def expect_drawn(state, frame, t, query, renderer="webgl2"):
    """The page drew the frame asked for, with WebGL2, no errors, no request."""
    check(state.get("ready") is True, f"?{query}: not ready: messages {state.get('messages')}")
    check(state["frame"] == frame, f"?{query}: frame {state['frame']}, asked for {frame}")
    check(state["t"] == t, f"?{query}: t = {state['t']!r}, the trajectory's t = {t!r}")
    check(state["errors"] == [], f"?{query}: errors {state['errors']}")
    check(state["resources"] == [], f"?{query}: the page requested {state['resources']}")
    check(state["renderer"] == renderer, f"?{query}: renderer {state['renderer']}, expected {renderer}")


def read_trajectory(run_dir, ambient):
    """Rows of trajectory.csv as (t, [embedding point of each body])."""
    lines = (run_dir / "trajectory.csv").read_text().splitlines()
    header = lines[0].split(",")
    bodies = sorted({int(m.group(1)) for h in header if (m := re.fullmatch(r"b(\d+)_x1", h))})
    columns = [[header.index(f"b{b}_x{i}") for i in range(1, ambient + 1)] for b in bodies]
    rows = []
    for line in lines[1:]:
        cells = line.split(",")
        rows.append((float(cells[0]), [[float(cells[c]) for c in cs] for cs in columns]))
    return rows


# ---- projections (projected-plane units; docs/view.md) -------------------------------------------

def poincare(x, R):
    """Disc/ball (H^n) and stereographic from the south pole (S^n): u = x_{1..n} / (R + x_{n+1})."""
    return [c / (R + x[-1]) for c in x[:-1]]


def pole_turn(x, k, sign):
    """The quarter turn in the (x_k, x_last) plane that takes sign R e_k to the north pole R e_last:
    y_last' = sign y_k, y_k' = -sign y_last (the other coordinates unchanged)."""
    y = list(x)
    y[-1], y[k] = sign * x[k], -sign * x[-1]
    return y


def cayley(x, R):
    """Upper half-plane: w = i (1 + u) / (1 - u), u the disc point (CFKP 1997, section 7)."""
    u = complex(*poincare(x, R))
    w = 1j * (1 + u) / (1 - u)
    return [w.real, w.imag]


def minkowski(a, b):
    return sum(p * q for p, q in zip(a[:-1], b[:-1])) - a[-1] * b[-1]


def hyperbolic_distance(a, b, R):
    return R * math.acosh(max(1.0, -minkowski(a, b) / (R * R)))


def rounding_bound(f, z):
    """First-order bound on |f(z) - f(fl32(z))| for a relative rounding 2^-24 of each input
    coordinate: sum_k |df/dz_k| |z_k| 2^-24 (central differences for the derivatives)."""
    total = 0.0
    for k, zk in enumerate(z):
        h = abs(zk) * 1e-6 + 1e-9
        up, down = list(z), list(z)
        up[k] += h
        down[k] -= h
        d = math.dist(f(up), f(down)) / (2 * h)
        total += d * abs(zk) * F32
    return total


def camera_apply(camera, p):
    c = [sum(camera[3 * r + k] * p[k] for k in range(3)) for r in range(3)]
    return [c[0], -c[1]]  # screen y grows downwards


def expect_positions(state, expected, query, what, bodies=None):
    """expected[b] = (plane (px, py) offsets from the origin in plane units before scaling,
    bound in plane units from the data's rounding, |P| of the projected point)."""
    ox, oy = state["origin"]
    s = state["scale"]
    screen = state["screen"]
    check(len(screen) == min(len(expected), 256),
          f"?{query}: {len(screen)} screen positions for {len(expected)} bodies")
    worst = 0.0
    for b in (range(len(expected)) if bodies is None else bodies):
        (px, py), bound_plane, norm = expected[b]
        x, y, visible = screen[b]
        check(visible == 1,
              f"?{query}: {what}: body {b} is not visible (expected at {ox + s * px:.2f}, {oy + s * py:.2f})")
        # scale * bound: the data's float32 rounding carried through the projection; scale * |P| 2^-24
        # * 2: the page's Float32Array of projected points (and the camera's rotation of it); SLACK:
        # the page's float64 pixel arithmetic. The state's positions are not rounded to pixels.
        bound = s * bound_plane + s * norm * F32 * 2 + screen_rounding(x, y) + screen_rounding(ox, oy)
        err = math.hypot(x - (ox + s * px), y - (oy + s * py))
        check(err <= bound, f"?{query}: {what}: body {b} at ({x:.4f}, {y:.4f}), expected "
                            f"({ox + s * px:.4f}, {oy + s * py:.4f}): off by {err:.3g} px > {bound:.3g} px")
        worst = max(worst, err)
    print(f"?{query}: {what}: positions within {worst:.2g} px (scale {s:.4g} px per unit)")


def planar(project, xs):
    """2-D views: screen offset (u1, -u2)."""
    out = []
    for x in xs:
        f = (lambda z: (lambda p: [p[0], -p[1]])(project(z)))
        p = f(x)
        out.append((p, rounding_bound(f, x), math.hypot(*p)))
    return out


def spatial(project, xs, camera):
    """3-D views: screen offset from the camera's rotation of the projected (x, y, z)."""
    out = []
    for x in xs:
        f = (lambda z: camera_apply(camera, project(z)))
        p = project(x)
        out.append((f(x), rounding_bound(f, x), math.sqrt(sum(c * c for c in p))))
    return out


# ---- PNG (screenshots) -------------------------------------------------------------------------

def read_png(path):
    """8-bit RGB or RGBA PNG -> (width, height, channels, rows of bytes). zlib + struct only."""
    data = path.read_bytes()
    check(data[:8] == b"\x89PNG\r\n\x1a\n", f"{path}: not a PNG")
    pos, idat = 8, b""
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            check(depth == 8 and colour in (2, 6) and interlace == 0, f"{path}: PNG type {depth}/{colour}/{interlace}")
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    channels = 3 if colour == 2 else 4
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, previous = [], bytearray(stride)
    for r in range(height):
        kind = raw[r * (stride + 1)]
        line = bytearray(raw[r * (stride + 1) + 1:(r + 1) * (stride + 1)])
        if kind == 1:
            for i in range(channels, stride):
                line[i] = (line[i] + line[i - channels]) & 255
        elif kind == 2:
            line = bytearray((a + b) & 255 for a, b in zip(line, previous))
        elif kind == 3:
            for i in range(stride):
                left = line[i - channels] if i >= channels else 0
                line[i] = (line[i] + ((left + previous[i]) >> 1)) & 255
        elif kind == 4:
            for i in range(stride):
                a = line[i - channels] if i >= channels else 0
                b = previous[i]
                c = previous[i - channels] if i >= channels else 0
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        else:
            check(kind == 0, f"{path}: PNG row filter {kind}")
        rows.append(line)
        previous = line
    return width, height, channels, rows


def pixel(png, x, y):
    width, height, channels, rows = png
    return tuple(rows[y][x * channels:x * channels + 3])


def colour_distance(a, b):
    return max(abs(p - q) for p, q in zip(a, b))


# Colour bound: the page's colours are 0-255 integers; a drawn colour goes through the GL's
# conversion to 8 bits (+-1) and the PNG is lossless.
COLOUR_BOUND = 2


def expect_pixels(ctx, page, query, state, what):
    """Screenshot: the pixel under each visible body has its colour; pixels far from every body
    are the canvas's background (its most common colour), which no body has."""
    png_path, _ = ctx.browse(page, query, screenshot=True)
    png = read_png(png_path)
    width, height = png[0], png[1]
    canvas = state["canvas"]
    left, top = int(canvas["left"]) + 2, int(canvas["top"]) + 2
    right = min(width, int(canvas["left"] + canvas["width"])) - 2
    bottom = min(height, int(canvas["top"] + canvas["height"])) - 2
    counts = {}
    for y in range(top, bottom, 7):
        for x in range(left, right, 7):
            c = pixel(png, x, y)
            counts[c] = counts.get(c, 0) + 1
    background = max(counts, key=counts.get)
    points = [(x, y) for x, y, v in state["screen"] if v]
    radius = state["point_px"] / 2
    checked = 0
    for b, (x, y, visible) in enumerate(state["screen"]):
        # a body covered by another (closer than a point's diameter and 2 px) is not checked
        if not visible or any(math.hypot(x - p, y - q) < 2 * radius + 2 for j, (p, q, v) in
                              enumerate(state["screen"]) if v and j != b):
            continue
        if not (left <= x < right and top <= y < bottom):
            continue
        got = pixel(png, int(x), int(y))
        want = tuple(state["colours"][b])
        check(colour_distance(got, want) <= COLOUR_BOUND,
              f"?{query}: {what}: pixel under body {b} at ({int(x)}, {int(y)}) is {got}, its colour is {want}")
        # (a body coloured like the background would make the check above prove nothing)
        check(colour_distance(want, background) > 16, f"?{query}: body {b}'s colour {want} is the background's")
        checked += 1
    check(checked > 0, f"?{query}: {what}: no body to check in the screenshot")
    print(f"?{query}: {what}: {checked} bodies drawn in their colours")
    # pixels farther than 4 point radii + 4 px from every body, on a coarse grid: background or a line,
    # so most of them must be the background.
    far = [(x, y) for y in range(top, bottom, 23) for x in range(left, right, 23)
           if all(math.hypot(x - p, y - q) > 4 * radius + 4 for p, q in points)]
    background_share = sum(pixel(png, x, y) == background for x, y in far) / max(1, len(far))
    check(len(far) > 50 and background_share > 0.8,
          f"?{query}: {what}: only {background_share:.0%} of {len(far)} pixels far from the bodies are the background")
    return png, background


# ---- scenes --------------------------------------------------------------------------------------

def scene(name, space, bodies, t_end=1.0, dt=0.01, output_every=10, potential=""):
    """bodies: [(x, v)] embedding points and velocities."""
    lines = [f'name = "{name}"', "[space]"] + [f"{k} = {json.dumps(v)}" for k, v in space.items()]
    for x, v in bodies:
        lines += ["[[bodies]]", "mass = 1.0", f"x = [{', '.join(repr(c) for c in x)}]",
                  f"v = [{', '.join(repr(c) for c in v)}]"]
    lines += [potential, "[integrator]", 'method = "sesi4"', f"dt = {dt!r}", f"t_end = {t_end!r}",
              f"output_every = {output_every}"]
    return "\n".join(lines) + "\n"


def sphere_point(R, angles):
    """A point of S^n from hyperspherical angles (last coordinate = R cos a_1: the north pole at a_1 = 0)."""
    n = len(angles)
    x = [0.0] * (n + 1)
    x[n] = R * math.cos(angles[0])
    s = R * math.sin(angles[0])
    for i in range(1, n):
        x[n - i] = s * math.cos(angles[i])
        s *= math.sin(angles[i])
    x[0] = s
    return x


def sphere_tangent(x, R, w):
    """w projected to the tangent space at x."""
    d = sum(a * b for a, b in zip(x, w)) / (R * R)
    return [b - d * a for a, b in zip(x, w)]


def hyperbolic_point(R, d, direction):
    """The point at distance d from the origin (0, .., 0, R) along the unit vector direction."""
    norm = math.sqrt(sum(c * c for c in direction))
    return [R * math.sinh(d / R) * c / norm for c in direction] + [R * math.cosh(d / R)]


S2_R = 1.5
# body 0 at the north pole to 1e-7 R (at rest: no potential, so it stays there; the scene reader
# refuses a body exactly on the chart's singular point); the others at polar angle a, azimuth phi,
# some moving along great circles.
POLE = 1e-7
S2_BODIES = [((POLE, 0.0), (0, 0, 0)), ((1.0, 0.3), (0.2, 0.1, 0)), ((2.0, 2.5), (0, 0, 0)),
             ((0.6, -2.0), (0, 0.3, 0.1)), ((1.4, 1.2), (-0.2, 0.2, 0.0)), ((2.3, -0.9), (0, 0, 0))]


def s2_scene():
    bodies = []
    for pos, vel in S2_BODIES:
        x = sphere_point(S2_R, [pos[0], pos[1]])
        bodies.append((x, sphere_tangent(x, S2_R, vel)))
    return scene("s2", {"kind": "sphere", "dim": 2, "radius": S2_R}, bodies)


def frame_and_points(run_dir, ambient, k):
    rows = read_trajectory(run_dir, ambient)
    t, xs = rows[k]
    return t, xs, len(rows)


# ---- cases ---------------------------------------------------------------------------------------

@case
def s2_stereographic(ctx):
    """S^2 stereographic: the north-pole body at the origin, every body at x_{1,2} / (R + x_3)."""
    run = ctx.sesi_run(s2_scene(), "s2")
    page, _ = ctx.sesi_view(run)
    k = 5
    t, xs, frames = frame_and_points(run, 3, k)
    check(math.hypot(*xs[0][:2]) <= POLE * S2_R, f"body 0 left the north pole: {xs[0]}")
    query = f"frame={k}&projection=stereographic&trail=0"
    st = ctx.state(page, query)
    expect_drawn(st, k, t, query)
    check(st["frames"] == frames and st["space"] == "S^2" and st["projection"] == "stereographic",
          f"?{query}: frames {st['frames']}, space {st['space']}, projection {st['projection']}")
    check(st["camera"] is None, f"?{query}: a 2-D view with a camera {st['camera']}")
    # the pole: |u| = tan(a / 2) <= POLE / 2 (+ the rounding of the f32 array)
    check(math.hypot(st["screen"][0][0] - st["origin"][0], st["screen"][0][1] - st["origin"][1])
          <= st["scale"] * (POLE / 2 + 2 * F32) + screen_rounding(*st["screen"][0][:2])
          + screen_rounding(*st["origin"]),
          f"?{query}: the north-pole body at {st['screen'][0][:2]}, the origin is {st['origin']}")
    expect_positions(st, planar(lambda x: poincare(x, S2_R), xs), query, "stereographic")
    expect_pixels(ctx, page, query, st, "stereographic")
    # A chosen pole, +x1 (`pole=1`): the quarter turn in the (x1, x3) plane taking R e1 to R e3 (y3' = y1,
    # y1' = -y3) first; a bad pole gets a banner.
    query = f"frame={k}&projection=stereographic&pole=1"
    st = ctx.state(page, query)
    expect_drawn(st, k, t, query)
    expect_positions(st, planar(lambda x: poincare(pole_turn(x, 0, +1), S2_R), xs), query, "stereographic, pole +x1")
    query = f"frame={k}&pole=7"
    st = ctx.state(page, query)
    check(any("pole=7" in m for m in st["messages"]), f"?{query}: no banner for a bad pole: {st['messages']}")


@case
def s2_globe(ctx):
    """S^2 as a globe (the default projection): screen = origin + scale (C x / R)_xy."""
    run = ctx.sesi_run(s2_scene(), "s2")
    page, _ = ctx.sesi_view(run)
    k = 10
    t, xs, _ = frame_and_points(run, 3, k)
    query = f"frame={k}"
    st = ctx.state(page, query)
    expect_drawn(st, k, t, query)
    check(st["projection"] == "sphere" and st["projections"][:2] == ["sphere", "stereographic"],
          f"?{query}: projection {st['projection']} of {st['projections']}")
    camera = st["camera"]
    check(camera is not None and len(camera) == 9, f"?{query}: camera {camera}")
    # C is a rotation: C C^T = 1 (float64 round-off, 1e-12 is far above it)
    for i in range(3):
        for j in range(3):
            dot = sum(camera[3 * i + k] * camera[3 * j + k] for k in range(3))
            check(abs(dot - (i == j)) < 1e-12, f"?{query}: the camera is not a rotation: {camera}")
    # the globe shows both hemispheres (the far side dimmed): every body has a position
    expect_positions(st, spatial(lambda x: [c / S2_R for c in x], xs, camera), query, "globe")


H2_R = 2.0
# (distance / R, angle): the hyperbolic distance d from the origin and the direction theta
# (body 0 at the origin to 1e-7 R: the scene reader refuses the chart's singular point itself)
H2_BODIES = [(POLE, 0.0), (0.5, 0.4), (2.0, 2.0), (6.0, -1.9), (1.0, -0.5)]


def h2_scene(genus=None, R=H2_R, bodies=H2_BODIES):
    xs = [(hyperbolic_point(R, d * R, [math.cos(a), math.sin(a)]), [0.0, 0.0, 0.0]) for d, a in bodies]
    space = {"kind": "hyperbolic", "dim": 2, "radius": R}
    if genus:
        space["genus"] = genus
    return scene("h2" if not genus else "genus2", space, xs)


@case
def h2_disc(ctx):
    """H^2 in the Poincare disc: a body at distance d from the origin at Euclidean radius
    scale tanh(d / 2R) along its angle."""
    run = ctx.sesi_run(h2_scene(), "h2")
    page, _ = ctx.sesi_view(run)
    t, xs, _ = frame_and_points(run, 3, 0)
    query = "frame=0&trail=0"
    st = ctx.state(page, query)
    expect_drawn(st, 0, t, query)
    check(st["projection"] == "disc" and st["projections"] == ["disc", "halfplane", "hyperboloid"],
          f"?{query}: projection {st['projection']} of {st['projections']}")
    ox, oy = st["origin"]
    s = st["scale"]
    for b, (d, angle) in enumerate(H2_BODIES):
        x, y, visible = st["screen"][b]
        radius = math.hypot(x - ox, y - oy)
        want = s * math.tanh(d / 2)
        # scale * 2^-24 cosh(d) * 2: float32 of the data (x_last = R cosh(d/R) carries a relative
        # 2^-24 that the disc map turns into ~2^-24 cosh(d/R) of |u| at most), twice for the page's
        # Float32Array of projected points
        bound = s * F32 * math.cosh(d) * 2 + screen_rounding(x, y) + screen_rounding(ox, oy)
        check(visible == 1 and abs(radius - want) <= bound,
              f"?{query}: body {b} at d = {d} R drawn at radius {radius:.4f} px, scale tanh(d/2R) = {want:.4f} px")
        if d > 0:
            drawn = math.atan2(-(y - oy), x - ox)
            gap = abs(math.remainder(drawn - angle, 2 * math.pi))
            check(gap * radius <= bound, f"?{query}: body {b} drawn at angle {drawn:.6f}, placed at {angle}")
    expect_positions(st, planar(lambda x: poincare(x, H2_R), xs), query, "disc")
    expect_pixels(ctx, page, query, st, "disc")


@case
def h2_canvas2d(ctx):
    """The fallback without WebGL (renderer=canvas2d): the same positions, the bodies' colours
    under them, and a banner saying how it draws."""
    run = ctx.sesi_run(h2_scene(), "h2")
    page, _ = ctx.sesi_view(run)
    t, xs, _ = frame_and_points(run, 3, 0)
    query = "frame=0&trail=0&renderer=canvas2d"
    st = ctx.state(page, query)
    expect_drawn(st, 0, t, query, renderer="canvas2d")
    check(any("canvas 2D" in m for m in st["messages"]), f"?{query}: no banner for the fallback: {st['messages']}")
    expect_positions(st, planar(lambda x: poincare(x, H2_R), xs), query, "disc, canvas 2D")
    expect_pixels(ctx, page, query, st, "disc, canvas 2D")


@case
def h2_halfplane(ctx):
    """The upper half-plane: the Cayley image i (1 + u) / (1 - u) of each disc point."""
    run = ctx.sesi_run(h2_scene(), "h2")
    page, _ = ctx.sesi_view(run)
    t, xs, _ = frame_and_points(run, 3, 0)
    query = "frame=0&projection=halfplane&trail=0"
    st = ctx.state(page, query)
    expect_drawn(st, 0, t, query)
    check(st["projection"] == "halfplane", f"?{query}: projection {st['projection']}")
    expected = planar(lambda x: cayley(x, H2_R), xs)
    # the origin's image is i: one plane unit above the drawn origin
    check(math.dist(expected[0][0], [0.0, -1.0]) < 1e-6, "the Cayley image of the disc's centre is not i")
    # bodies 0 (w = i), 1 and 4 lie within the view (|w| < 3); the far ones may leave the window
    expect_positions(st, expected, query, "half-plane", bodies=[0, 1, 4])
    for b, (x, y, visible) in enumerate(st["screen"]):
        if visible:
            expect_positions(st, expected, query, "half-plane", bodies=[b])


@case
def h2_recentred(ctx):
    """centre=b: the view isometry brings body b to the origin, and every body c is then drawn at
    disc radius tanh(d(b, c) / 2R)."""
    run = ctx.sesi_run(h2_scene(), "h2")
    page, _ = ctx.sesi_view(run)
    t, xs, _ = frame_and_points(run, 3, 0)
    for b in (2, 3):
        query = f"frame=0&centre={b}&trail=0"
        st = ctx.state(page, query)
        expect_drawn(st, 0, t, query)
        ox, oy = st["origin"]
        s = st["scale"]
        check(math.hypot(st["screen"][b][0] - ox, st["screen"][b][1] - oy)
              <= s * F32 * 2 + screen_rounding(*st["screen"][b][:2]) + screen_rounding(ox, oy),
              f"?{query}: body {b} drawn at {st['screen'][b][:2]}, the origin is {st['origin']}")
        for c in range(len(xs)):
            f = (lambda z: [math.tanh(hyperbolic_distance(z[:3], z[3:], H2_R) / (2 * H2_R)), 0.0])
            want = f(xs[b] + xs[c])[0]
            # rounding of both points' data carried into tanh(d / 2R), plus pixels and the f32 array
            bound = (s * (rounding_bound(f, xs[b] + xs[c]) + 2 * F32) + screen_rounding(*st["screen"][c][:2])
                     + screen_rounding(ox, oy))
            radius = math.hypot(st["screen"][c][0] - ox, st["screen"][c][1] - oy)
            check(st["screen"][c][2] == 1 and abs(radius - s * want) <= bound,
                  f"?{query}: body {c} at radius {radius:.4f} px, scale tanh(d(b, c)/2R) = {s * want:.4f} px")


@case
def h2_hyperboloid(ctx):
    """The hyperboloid (3-D): p = (x1 / R, x2 / R, x0 / R - 1) through the camera."""
    run = ctx.sesi_run(h2_scene(bodies=H2_BODIES[:3] + [(1.5, -1.9)]), "h2")
    page, _ = ctx.sesi_view(run)
    t, xs, _ = frame_and_points(run, 3, 0)
    query = "frame=0&projection=hyperboloid"
    st = ctx.state(page, query)
    expect_drawn(st, 0, t, query)
    check(st["camera"] is not None, f"?{query}: no camera in a 3-D view")
    expected = spatial(lambda x: [x[0] / H2_R, x[1] / H2_R, x[2] / H2_R - 1], xs, st["camera"])
    for b, (_, _, visible) in enumerate(st["screen"]):
        if visible:
            expect_positions(st, expected, query, "hyperboloid", bodies=[b])
    check(st["screen"][0][2] == 1, f"?{query}: the body at the origin is not visible")


@case
def s3_stereographic(ctx):
    """S^3: stereographic projection into R^3 from the south pole, through the camera."""
    R = 1.0
    angles = [(POLE, 0.7, 0.9), (0.8, 0.5, 1.0), (1.5, 2.0, -2.0), (2.0, 1.0, 0.5), (1.1, 0.3, 2.8)]
    bodies = []
    for a in angles:
        x = sphere_point(R, list(a))
        bodies.append((x, sphere_tangent(x, R, [0.1, -0.2, 0.15, 0.0])))
    run = ctx.sesi_run(scene("s3", {"kind": "sphere", "dim": 3, "radius": R}, bodies), "s3")
    page, _ = ctx.sesi_view(run)
    k = 4
    t, xs, _ = frame_and_points(run, 4, k)
    query = f"frame={k}"
    st = ctx.state(page, query)
    expect_drawn(st, k, t, query)
    check(st["projection"] == "stereographic" and st["space"] == "S^3", f"?{query}: {st['space']} {st['projection']}")
    expect_positions(st, spatial(lambda x: poincare(x, R), xs, st["camera"]), query, "S^3 stereographic")
    # A chosen pole, -x1: the view turns the sphere by the quarter turn in the (x1, x4) plane that takes -R e1
    # to the north pole R e4 (y4' = -y1, y1' = y4), then projects from the new south pole.
    query = f"frame={k}&pole=-1"
    st = ctx.state(page, query)
    expect_drawn(st, k, t, query)
    expect_positions(st, spatial(lambda x: poincare(pole_turn(x, 0, -1), R), xs, st["camera"]), query,
                     "S^3 stereographic, pole -x1")


@case
def h3_ball(ctx):
    """H^3 in the Poincare ball: u = x_{1..3} / (R + x_4), |u| = tanh(d / 2R), through the camera."""
    R = 1.3
    places = [(POLE, (1, 0, 0)), (0.7, (1, 2, -1)), (2.0, (-1, 0.5, 0.3)), (4.0, (0.2, -1, 0.7)), (1.2, (0.1, 0.2, 1))]
    bodies = [(hyperbolic_point(R, d * R, direction), [0.0] * 4) for d, direction in places]
    run = ctx.sesi_run(scene("h3", {"kind": "hyperbolic", "dim": 3, "radius": R}, bodies), "h3")
    page, _ = ctx.sesi_view(run)
    t, xs, _ = frame_and_points(run, 4, 0)
    query = "frame=0"
    st = ctx.state(page, query)
    expect_drawn(st, 0, t, query)
    check(st["projection"] == "ball" and st["space"] == "H^3", f"?{query}: {st['space']} {st['projection']}")
    for x, (d, _) in zip(xs, places):
        check(abs(math.sqrt(sum(c * c for c in poincare(x, R))) - math.tanh(d / 2)) < 1e-12, "ball radius formula")
    expect_positions(st, spatial(lambda x: poincare(x, R), xs, st["camera"]), query, "ball")


@case
def s4_first_coordinates(ctx):
    """S^4: stereographic into R^4, then the first 3 coordinates; the page says so."""
    R = 1.0
    bodies = []
    for a in [(0.3, 0.2, 0.4, 0.5), (1.2, 1.0, 2.0, -1.0), (2.0, 0.5, 1.5, 2.5), (0.9, 2.5, 0.7, 0.1)]:
        x = sphere_point(R, list(a))
        bodies.append((x, [0.0] * 5))
    run = ctx.sesi_run(scene("s4", {"kind": "sphere", "dim": 4, "radius": R}, bodies), "s4")
    page, _ = ctx.sesi_view(run)
    t, xs, _ = frame_and_points(run, 5, 0)
    query = "frame=0"
    st = ctx.state(page, query)
    expect_drawn(st, 0, t, query)
    check("first 3" in st["note"], f"?{query}: the note {st['note']!r} does not say which coordinates are shown")
    expect_positions(st, spatial(lambda x: poincare(x, R)[:3], xs, st["camera"]), query, "S^4 first 3")
    # Chosen coordinates (axes=4,1,3, 1-based): u_4, u_1, u_3 in that order, and the note says so.
    query = "frame=0&axes=4,1,3"
    st = ctx.state(page, query)
    expect_drawn(st, 0, t, query)
    check(st["note"] == "coordinates 4, 1, 3 of 4", f"?{query}: the note {st['note']!r}")
    expect_positions(st, spatial(lambda x: [poincare(x, R)[k] for k in (3, 0, 2)], xs, st["camera"]), query,
                     "S^4 axes 4, 1, 3")
    query = "frame=0&axes=1,1,2"
    st = ctx.state(page, query)
    check(any("axes=1,1,2" in m for m in st["messages"]), f"?{query}: no banner for bad axes: {st['messages']}")


@case
def one_dimensional(ctx):
    """S^1 (circle: p = x / R), H^1 (the disc's interval: u = x_1 / (R + x_2)) and the E^1 box
    (p = x mod L - L/2), each drawn where its formula puts it."""
    R = 1.5
    spaces = {
        "s1": ({"kind": "sphere", "dim": 1, "radius": R},
               [([R * math.cos(a), R * math.sin(a)], [-0.3 * math.sin(a), 0.3 * math.cos(a)]) for a in (0.3, 2.0, 4.0)],
               lambda x: [x[0] / R, -x[1] / R]),
        "h1": ({"kind": "hyperbolic", "dim": 1, "radius": R},
               [([R * math.sinh(d), R * math.cosh(d)], [0.0, 0.0]) for d in (-2.0, 0.5, 3.0)],
               lambda x: [x[0] / (R + x[1]), 0.0]),
        "e1": ({"kind": "euclidean", "dim": 1, "box": [10.0]},
               [([c], [0.7]) for c in (1.0, 4.0, 9.5)],
               lambda x: [wrap(x[0], 10.0) - 5.0, 0.0]),
    }
    for name, (space, bodies, plane) in spaces.items():
        run = ctx.sesi_run(scene(name, space, bodies), name)
        page, _ = ctx.sesi_view(run)
        k = 3
        t, xs, _ = frame_and_points(run, len(bodies[0][0]), k)
        query = f"frame={k}&trail=0"
        st = ctx.state(page, query)
        expect_drawn(st, k, t, query)
        check(st["camera"] is None, f"?{query}: {name}: a camera in a 2-D view")
        expected = [(plane(x), rounding_bound(plane, x), math.hypot(*plane(x))) for x in xs]
        expect_positions(st, expected, query, name)


E2_BOX = [10.0, 6.0]


def wrap(c, L):
    return c - L * math.floor(c / L)


@case
def e2_box(ctx):
    """E^2 box: screen = origin + scale (x - L/2, -(y - L/2)): affine in x, the box centred."""
    places = [(1.0, 1.0), (9.0, 5.0), (5.0, 3.0), (2.5, 4.5), (7.5, 0.5), (0.0, 0.0)]
    bodies = [(list(p), [1.3, -0.4]) for p in places]
    run = ctx.sesi_run(scene("e2", {"kind": "euclidean", "dim": 2, "box": E2_BOX}, bodies), "e2")
    page, _ = ctx.sesi_view(run)
    k = 7
    t, xs, _ = frame_and_points(run, 2, k)
    query = f"frame={k}&trail=0"
    st = ctx.state(page, query)
    expect_drawn(st, k, t, query)
    check(st["projection"] == "flat" and st["camera"] is None, f"?{query}: {st['projection']} {st['camera']}")
    # the page shows each body in the domain [0, L) (a run's point may stand outside it by up to the
    # wrap margin between wraps, docs/scene-format.md): x mod L
    expect_positions(st, planar(lambda x: [wrap(c, L) - L / 2 for c, L in zip(x, E2_BOX)], xs), query, "E^2 box")
    expect_pixels(ctx, page, query, st, "E^2 box")


@case
def e3_box(ctx):
    """E^3 box (3-D): p = x - L/2 through the camera."""
    box = [8.0, 6.0, 4.0]
    places = [(1.0, 1.0, 1.0), (7.0, 5.0, 3.0), (4.0, 3.0, 2.0), (2.0, 5.5, 0.5)]
    bodies = [(list(p), [0.5, 0.2, -0.3]) for p in places]
    run = ctx.sesi_run(scene("e3", {"kind": "euclidean", "dim": 3, "box": box}, bodies), "e3")
    page, _ = ctx.sesi_view(run)
    k = 3
    t, xs, _ = frame_and_points(run, 3, k)
    query = f"frame={k}"
    st = ctx.state(page, query)
    expect_drawn(st, k, t, query)
    expect_positions(st, spatial(lambda x: [wrap(c, L) - L / 2 for c, L in zip(x, box)], xs, st["camera"]), query,
                     "E^3 box")


@case
def genus2_surface(ctx):
    """The Bolza surface (genus 2) in the disc: bodies as in H^2, and the octagon's sides drawn
    through the geodesic midpoints of the meta's vertices."""
    R = 1.0
    places = [(POLE, 0.0), (0.5, 0.3), (0.9, 2.2), (0.7, -2.0), (0.4, 4.0)]
    run = ctx.sesi_run(h2_scene(genus=2, R=R, bodies=places), "genus2")
    page, _ = ctx.sesi_view(run)
    t, xs, _ = frame_and_points(run, 3, 0)
    meta = read_meta(page)
    vertices = meta["polygon"]["vertices"]
    check(len(vertices) == 8, f"{len(vertices)} polygon vertices for genus 2")
    for query in ("frame=0&trail=0", "frame=0&trail=0&tiles=1"):
        st = ctx.state(page, query)
        expect_drawn(st, 0, t, query)
        expect_positions(st, planar(lambda x: poincare(x, R), xs), query, "genus-2 disc")
    query = "frame=0&trail=0"
    st = ctx.state(page, query)
    png, background = expect_pixels(ctx, page, query, st, "genus-2 disc")
    ox, oy = st["origin"]
    s = st["scale"]
    for j in range(8):
        a, b = vertices[j], vertices[(j + 1) % 8]
        m = [p + q for p, q in zip(a, b)]
        norm = math.sqrt(-minkowski(m, m))
        m = [c * R / norm for c in m]  # the geodesic midpoint of a and b (Ratcliffe, section 3.2)
        u = poincare(m, R)
        x, y = ox + s * u[0], oy - s * u[1]
        # a 1-px line through (x, y): some pixel within 2 px (1 px width + 0.5 px rounding) is not background
        near = [pixel(png, int(x) + i, int(y) + k) for i in range(-2, 3) for k in range(-2, 3)]
        check(any(colour_distance(c, background) > 16 for c in near),
              f"?{query}: no line drawn at the midpoint of polygon side {j} ({x:.1f}, {y:.1f})")


def read_meta(page):
    return read_meta_text(page.read_text())


def read_meta_text(text):
    m = re.search(r'<script type="application/json" id="sesi-meta">(.*?)</script>', text, re.S)
    check(m is not None, "the page has no #sesi-meta")
    return json.loads(m.group(1).replace("<\\/", "</"))


def guard_scene():
    """A harmonic pair on E^2 stepped beyond Strang's stability limit (w dt = 2.04): the energy
    guard stops it (exit 3), an unfinished run (tests/program/run/cases_run.py)."""
    return "\n".join(['name = "stiff"', "[space]", 'kind = "euclidean"', "dim = 2",
                      "[[bodies]]", "mass = 1.0", "q = [1.0, 1.0]", "p = [0.0, 0.3]",
                      "[[bodies]]", "mass = 1.0", "q = [0.0, 0.0]", "p = [0.0, -0.3]",
                      "[[potential]]", 'kind = "harmonic-pair"', "k = 0.5",
                      "[integrator]", 'method = "sesi2"', "dt = 2.04", "t_end = 408.0"]) + "\n"


@case
def unfinished_run(ctx):
    """An unfinished run: the page draws the frames it wrote under a banner that says so."""
    run = ctx.sesi_run(guard_scene(), "stiff", expect=3)
    page, r = ctx.sesi_view(run)
    check(r.stderr.strip() != "", "sesi view of an unfinished run says nothing on stderr")
    query = "frame=0"
    st = ctx.state(page, query)
    t, _, _ = frame_and_points(run, 2, 0)
    expect_drawn(st, 0, t, query)
    check(any("finish" in m and "energy error exceeded" in m for m in st["messages"]),
          f"?{query}: no banner saying the run did not finish and why: {st['messages']}")


@case
def no_frames(ctx):
    """A run whose trajectory holds no frame (its header only) is refused by `sesi view` with one
    line; a page whose meta says zero frames shows a message, not a blank page."""
    run = ctx.sesi_run(s2_scene(), "s2")
    page, _ = ctx.sesi_view(run)
    text = page.read_text()
    page.unlink()
    trajectory = run / "trajectory.csv"
    trajectory.write_text(trajectory.read_text().splitlines()[0] + "\n")
    r = subprocess.run([ctx.sesi, "view", str(run), "--quiet"], capture_output=True, text=True, timeout=60)
    check(r.returncode == 2 and r.stderr.count("\n") == 1 and not page.exists(),
          f"sesi view of a run with no frames: exit {r.returncode}, {r.stderr!r}, page written: {page.exists()}")
    meta = read_meta_text(text)
    meta["frames"].update(count=0, t=[])
    empty = ctx.work / "empty.html"
    empty.write_text(replace_script(replace_script(text, "sesi-meta", json.dumps(meta).replace("</", "<\\/")),
                                    "sesi-frames", ""))
    st = ctx.state(empty, "")
    check(st["errors"] == [] and any("no frames" in m for m in st["messages"]),
          f"a page of zero frames: messages {st['messages']}, errors {st['errors']}")
    expect_visible_text(ctx, empty, "", [m for m in st["messages"] if "no frames" in m][0])


def replace_script(text, element, content):
    pattern = r'(<script type="[^"]*" id="%s">)(.*?)(</script>)' % element
    new, n = re.subn(pattern, lambda m: m.group(1) + content + m.group(3), text, count=1, flags=re.S)
    check(n == 1, f"the page has no #{element} element")
    return new


def expect_visible_text(ctx, page, query, text):
    dom, _ = ctx.browse(page, query)
    body = re.sub(r"<script.*?</script>", "", dom, flags=re.S)
    words = html.unescape(re.sub(r"<[^>]+>", " ", body))
    check(text.split(".")[0][:40] in " ".join(words.split()),
          f"?{query}: the message {text!r} is not in the page's text")


@case
def broken_page(ctx):
    """A page whose frames (or meta) were emptied, as in a broken file: a message naming what,
    never a blank page."""
    run = ctx.sesi_run(s2_scene(), "s2")
    page, _ = ctx.sesi_view(run)
    text = page.read_text()
    for what in ("frames", "meta"):
        broken = ctx.work / f"broken-{what}.html"
        broken.write_text(replace_script(text, f"sesi-{what}", ""))
        dom, _ = ctx.browse(broken, "frame=1")
        st = parse_state(dom, what)
        check(st.get("messages"), f"a page with its {what} emptied shows no message: {st}")
        expect_visible_text(ctx, broken, "frame=1", st["messages"][0])


@case
def serve_stream(ctx):
    """`sesi view --serve`: the stream page fetches frames/<k> from the server (on 127.0.0.1 in an
    empty network namespace) and draws the frame asked for where the projection puts it; its only
    requests are those frames; SIGINT stops the server with exit status 0."""
    run = ctx.sesi_run(s2_scene(), "s2")
    server = subprocess.Popen([ctx.sesi, "view", str(run), "--serve", "--port", "0"], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    try:
        line = server.stdout.readline()
        m = re.search(r"http://127\.0\.0\.1:\d+/", line)
        check(m is not None, f"sesi view --serve printed {line!r}")
        k = 5
        t, xs, _ = frame_and_points(run, 3, k)
        query = f"frame={k}&projection=stereographic&trail=0"
        # the frame is drawn when its fetch resolves
        st = ctx.state_when_drawn(m.group(0), query)
        # (the page writes its state when the frame is drawn, which may come before the browser
        # lists the fetch among its resources: the list may be empty)
        # favicon.ico: the browser's own request for an http page's icon, not the page's
        check(all(re.fullmatch(re.escape(m.group(0)) + r"(frames/\d+|favicon\.ico)", r) for r in st["resources"]),
              f"?{query}: requests other than frames/<k>: {st['resources']}")
        st["resources"] = []
        expect_drawn(st, k, t, query)
        expect_positions(st, planar(lambda x: poincare(x, S2_R), xs), query, "stream page")
    finally:
        server.send_signal(signal.SIGINT)
        try:
            code = server.wait(timeout=30)
        except subprocess.TimeoutExpired:
            server.kill()
            raise Failure("sesi view --serve did not stop within 30 s of SIGINT")
    check(code == 0, f"sesi view --serve ended with exit status {code} after SIGINT: {server.stderr.read()!r}")
    check(not (run / "view.html").exists(), "sesi view --serve wrote view.html")


NEEDS_LOOPBACK = {"serve_stream"}


@case
def geometry_module(ctx):
    """tests/view/geometry_test.html: the geometry module's own checks, in the browser."""
    page = ctx.source / "tests" / "view" / "geometry_test.html"
    dom, _ = ctx.browse(page, canvas=False)
    m = re.search(r'<pre id="result">(.*?)</pre>', dom, re.S)
    check(m is not None, f"geometry_test.html wrote no result: {dom[-500:]!r}")
    result = json.loads(html.unescape(m.group(1)))
    check(result["failures"] == [], f"geometry checks failed: {result['failures']}")
    check(result["passed"] > 0, f"no geometry check ran: {result}")
    print(f"geometry_test.html: {result['passed']} passed")


@case
def python_inline(ctx):
    """The Python package's page (sesi.view(DIR).save) and its Jupyter form (_repr_html_, an iframe
    with the page as srcdoc, saved in a file) draw the bodies."""
    run = ctx.sesi_run(s2_scene(), "s2")
    saved = ctx.work / "saved.html"
    wrapper = ctx.work / "wrapper.html"
    code = ("import sesi, sys\nv = sesi.view(sys.argv[1])\nv.save(sys.argv[2])\n"
            "open(sys.argv[3], 'w').write('<!doctype html><html><body style=\"margin:0\">' + v._repr_html_() + "
            "'</body></html>')\n")
    env = dict(os.environ, PYTHONPATH=ctx.pythonpath, PYTHONDONTWRITEBYTECODE="1")
    r = subprocess.run([sys.executable, "-c", code, str(run), str(saved), str(wrapper)], capture_output=True,
                       text=True, env=env, timeout=120)
    check(r.returncode == 0, f"sesi.view(...).save(...) failed: {r.stderr[-1000:]}")
    k = 5
    t, xs, _ = frame_and_points(run, 3, k)
    query = f"frame={k}&projection=stereographic&trail=0"
    st = ctx.state(saved, query)
    expect_drawn(st, k, t, query)
    expect_positions(st, planar(lambda x: poincare(x, S2_R), xs), query, "saved from Python")
    # the iframe: its own state is out of reach (sandboxed), so its screenshot must show the same
    # bodies in their full colours (the globe dims its far side) as the saved page's own screenshot
    st0 = ctx.state(saved, "")
    shown = {}
    for what, path, canvas in (("page", saved, True), ("iframe", wrapper, False)):
        png = read_png(ctx.browse(path, "", screenshot=True, canvas=canvas, in_process_iframes=True)[0])
        colours = {pixel(png, x, y) for y in range(png[1]) for x in range(png[0])}
        shown[what] = [b for b, want in enumerate(st0["colours"])
                       if any(colour_distance(c, tuple(want)) <= COLOUR_BOUND for c in colours)]
    check(shown["page"] and shown["iframe"] == shown["page"],
          f"bodies drawn in full colour: {shown['iframe']} in the Jupyter iframe, {shown['page']} in the page")


# ---- driver --------------------------------------------------------------------------------------

def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--list", action="store_true")
    parser.add_argument("--sesi")
    parser.add_argument("--chromium")
    parser.add_argument("--source", default=str(HERE.parent.parent))
    parser.add_argument("--work")
    parser.add_argument("--pythonpath", default="")
    parser.add_argument("--case")
    parser.add_argument("--in-namespace", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.list:
        print("\n".join(CASES))
        return 0
    if args.case not in CASES:
        print(f"check_view.py: no case {args.case!r}", file=sys.stderr)
        return 2
    if args.case in NEEDS_LOOPBACK and not args.in_namespace:
        # the server and the browser in one empty network namespace, with its loopback interface up
        inner = [sys.executable, *sys.argv, "--in-namespace"]
        ip = shutil.which("ip") or shutil.which("ip", path="/usr/sbin:/sbin")
        if ip and subprocess.run(["unshare", "-n", "true"], capture_output=True).returncode == 0:
            up = f'"{ip}" link set lo up && exec "$@"'
            return subprocess.run(["unshare", "-n", "sh", "-c", up, "sh", *inner]).returncode
        print("note: no `unshare -n` or no `ip` (iproute2) here: the server and Chromium use the machine's loopback")
    work = pathlib.Path(args.work) / args.case
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    args.work = str(work)
    ctx = Context(args)
    try:
        CASES[args.case](ctx)
    except Failure as e:
        print(f"FAILED {args.case}: {e}")
        return 1
    print(f"passed {args.case}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Tests `hairsim view` in a real browser: Chromium (headless), driven over the DevTools
protocol through a pipe (no driver, no websocket library).

  - N steps of each scene in the page give the state hash of `hairsim run SCENE --steps N --json`
    (built-in scenes loaded from the page's list, the hair file dropped on the page), with the
    `simd128` module and with the module without SIMD;
  - the page's stepping cost against `hairsim run --threads 1`'s, per scene and solver,
    alternated in one run (printed: timing is not asserted on a shared machine);
  - every effect box on a rod and a DFTL scene: a usable one switches, an unusable one is
    disabled with its reason;
  - drops through real drop events: a good hair file, a malformed one (an error naming the
    file, the old scene still running), a scene file with the hair file it names, and one
    without it;
  - a drag on a strand with synthetic mouse events: the grab force points toward the hand's
    target, grows as the drag lengthens, and is zero after release, on the rod (stand-1) and
    on DFTL (sintel_hair.tfx dropped: the strand follows, the force is plotted); the mouse grab
    is coupled: pulled 5 cm past the strand's reach it holds with the spring's force, pulled on
    it slips at its force limit, is drawn and marked on the plot, and a second press re-grabs
    it;
  - the rod with inextensibility off: stretch and roll-backs shown, "stuck" after a second of
    strands rolled back at every step; ticked back on, the hair recovers;
  - time: after a 15 s stall (the page's clock moved on at once) the page drops the lag and
    goes on in real time; a scene too heavy for real time says "slow motion";
  - the real-time ratio per scene and solver, asserted >= 0.99 for `firmware`;
  - no console error or uncaught exception;
  - screenshots: the followers drawn (hair pixels against the leaders-only picture), the
    strands shaded (many hair tones), docs/pictures/viewer.png.

Usage: viewer-test.py HAIRSIM_BINARY [--screenshot FILE] [--sweep] [--speed ROUNDS]
  --sweep: also find how many strands of each solver keep real time (for the docs; about a
    minute); --sweep-out FILE writes what it found as a table for benches/performance.py
    (benches/tables/viewer.json, which docs/performance.md shows).
  --speed ROUNDS: rounds of the page-against-native stepping cost (default 1).
  --only WORDS: the checks whose titles contain one of these comma-separated words.
  --url URL: test the page at URL instead of the one `hairsim view` serves.
HAIRSIM_SAMPLES must name the sample hair files' folder.
"""
import base64
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib

HAIR_FILE = "sintel_hair.tfx"
# (scene, steps) whose hashes are compared with the native run.
HASH_SCENES = [("firmware", 1000), ("firmware-dftl", 1000), ("head-2", 100)]
# DFTL strands held by grabs (two coupled, one prescribed): a block holding one steps strand by
# strand. Dropped on the page as a scene file.
HELD_SCENE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "dftl-grabs.toml")
REALTIME_SECONDS = 5.0


class Browser:
    """Chromium with `--remote-debugging-pipe`: commands in on fd 3, replies and events out on
    fd 4, each message one JSON text ended by a NUL byte."""

    def __init__(self):
        self.profile = tempfile.mkdtemp(prefix="hairsim-chromium-")
        to_browser_r, self.to_browser = os.pipe()
        self.from_browser, from_browser_w = os.pipe()

        def pipes():
            os.dup2(to_browser_r, 3)
            os.dup2(from_browser_w, 4)

        self.process = subprocess.Popen(
            [
                chromium(),
                "--headless=new",
                "--no-sandbox",
                "--remote-debugging-pipe",
                f"--user-data-dir={self.profile}",
                "--window-size=1280,900",
                "--no-first-run",
                "--disable-extensions",
                # A headless page counts as hidden; these keep its frames and timers at the
                # rate a visible tab gets.
                "--disable-background-timer-throttling",
                "--disable-renderer-backgrounding",
                "--disable-backgrounding-occluded-windows",
                "about:blank",
            ],
            preexec_fn=pipes,
            close_fds=False,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        os.close(to_browser_r)
        os.close(from_browser_w)
        self.buffer = b""
        self.next_id = 0
        self.events = []
        self.session = None

    def send(self, method, params=None, session=True):
        self.next_id += 1
        message = {"id": self.next_id, "method": method, "params": params or {}}
        if session and self.session:
            message["sessionId"] = self.session
        os.write(self.to_browser, json.dumps(message).encode() + b"\0")
        while True:
            reply = self.receive()
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            self.events.append(reply)

    def receive(self):
        while b"\0" not in self.buffer:
            chunk = os.read(self.from_browser, 1 << 20)
            if not chunk:
                raise RuntimeError("the browser closed its pipe")
            self.buffer += chunk
        message, self.buffer = self.buffer.split(b"\0", 1)
        return json.loads(message)

    def open(self, url):
        targets = self.send("Target.getTargets", session=False)["targetInfos"]
        page = next(t for t in targets if t["type"] == "page")
        self.session = self.send(
            "Target.attachToTarget", {"targetId": page["targetId"], "flatten": True}, session=False
        )["sessionId"]
        for domain in ["Runtime", "Log", "Page"]:
            self.send(f"{domain}.enable")
        # A fixed viewport, whatever the headless window's frame takes: the camera, and so
        # the world distance a mouse move means, depends on the canvas's size.
        self.send(
            "Emulation.setDeviceMetricsOverride",
            {"width": 1280, "height": 800, "deviceScaleFactor": 1, "mobile": False},
        )
        self.send("Page.navigate", {"url": url})

    def evaluate(self, expression, wait=True):
        result = self.send(
            "Runtime.evaluate",
            {"expression": expression, "returnByValue": True, "awaitPromise": wait},
        )
        if "exceptionDetails" in result:
            details = result["exceptionDetails"]
            raise RuntimeError(f"{expression}: {details.get('exception', {}).get('description', details)}")
        return result["result"].get("value")

    def mouse(self, kind, x, y, button="left", buttons=None):
        if buttons is None:
            buttons = 0 if kind == "mouseReleased" else 1
        self.send(
            "Input.dispatchMouseEvent",
            {"type": kind, "x": x, "y": y, "button": button, "buttons": buttons, "clickCount": 1},
        )

    def errors(self):
        """Console errors and uncaught exceptions so far."""
        found = []
        for event in self.events:
            method, params = event.get("method"), event.get("params", {})
            if method == "Runtime.exceptionThrown":
                found.append(params["exceptionDetails"].get("exception", {}).get("description", str(params)))
            elif method == "Runtime.consoleAPICalled" and params.get("type") == "error":
                found.append(" ".join(str(a.get("value", a.get("description"))) for a in params["args"]))
            elif method == "Log.entryAdded" and params["entry"]["level"] == "error":
                found.append(params["entry"]["text"])
        return found

    def close(self):
        try:
            self.send("Browser.close", session=False)
        except RuntimeError:
            pass
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
        shutil.rmtree(self.profile, ignore_errors=True)


def chromium():
    for name in ["chromium", "chromium-browser", "google-chrome"]:
        path = shutil.which(name)
        if path:
            return path
    sys.exit("no Chromium found (Debian: apt-get install chromium)")


def native_hash(binary, scene, steps):
    out = subprocess.run(
        [binary, "run", scene, "--steps", str(steps), "--json", "--threads", "1"],
        check=True, capture_output=True, text=True,
    ).stdout
    return json.loads(out)["state_hash"]


def png_pixels(data):
    """(width, height, rows of RGB tuples) of an 8-bit RGB or RGBA, non-interlaced PNG."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    at, idat, header = 8, b"", None
    while at < len(data):
        length, kind = struct.unpack(">I4s", data[at:at + 8])
        body = data[at + 8:at + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        at += 12 + length
    width, height, depth, colour, _, _, interlace = header
    assert depth == 8 and colour in (2, 6) and interlace == 0, header
    channels = 3 if colour == 2 else 4
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, previous, at = [], bytearray(stride), 0
    for _ in range(height):
        kind, line = raw[at], bytearray(raw[at + 1:at + 1 + stride])
        at += 1 + stride
        for i in range(stride):
            left = line[i - channels] if i >= channels else 0
            up, up_left = previous[i], previous[i - channels] if i >= channels else 0
            if kind == 1:
                line[i] = (line[i] + left) & 0xFF
            elif kind == 2:
                line[i] = (line[i] + up) & 0xFF
            elif kind == 3:
                line[i] = (line[i] + (left + up) // 2) & 0xFF
            elif kind == 4:
                p = left + up - up_left
                pa, pb, pc = abs(p - left), abs(p - up), abs(p - up_left)
                line[i] = (line[i] + (left if pa <= pb and pa <= pc else up if pb <= pc else up_left)) & 0xFF
        rows.append([tuple(line[i:i + 3]) for i in range(0, stride, channels)])
        previous = line
    return width, height, rows


def hair_coloured(rgb):
    """The page's hair runs from dark brown at the root to blond at the tip, lit and shaded:
    warm (red above green above blue) and brighter than the bluish-black background. The
    colliders are bluish grey, the warning colour pink."""
    r, g, b = rgb
    return r > 45 and r > g + 6 and g > b + 3


class Page:
    def __init__(self, browser, url):
        self.b = browser
        self.url = url

    def status(self):
        return self.b.evaluate("window.hairsim.status()")

    def wait_ready(self, timeout=30):
        end = time.time() + timeout
        while time.time() < end:
            ready = self.b.evaluate("!!(window.hairsim && window.hairsim.ready)")
            if ready:
                return
            time.sleep(0.2)
        raise RuntimeError(f"the page did not start: {self.b.errors()}")

    def navigate(self, query=""):
        self.b.send("Page.navigate", {"url": self.url + query})
        time.sleep(0.5)
        self.wait_ready()

    def error(self):
        return self.b.evaluate("window.hairsim.error()")

    def check_error(self, what):
        error = self.error()
        assert not error, f"{what}: the page shows an error: {error}"

    def load(self, scene):
        """Loads a built-in scene as a user does: picks it in the page's list."""
        self.b.evaluate(
            f"(() => {{ const s = document.getElementById('scene'); s.value = {json.dumps(scene)};"
            " s.dispatchEvent(new Event('change')); })()"
        )
        self.check_error(f"loading {scene}")
        assert self.status()["scene"] == scene, self.status()

    def drop(self, files, expect_error=None):
        """Drops files [(name, bytes)] on the page as a user does (one drop event), and waits
        until the first runs, or until the page shows an error starting with `expect_error`."""
        script = ["const transfer = new DataTransfer();"]
        for name, data in files:
            encoded = base64.b64encode(data).decode()
            script.append(
                "transfer.items.add(new File([Uint8Array.from(atob(" + json.dumps(encoded) + "), (c) => c.charCodeAt(0))], "
                + json.dumps(name) + "));"
            )
        script.append(
            "document.getElementById('stage').dispatchEvent(new DragEvent('drop', {dataTransfer: transfer, bubbles: true, cancelable: true}));"
        )
        self.b.evaluate("(() => {" + " ".join(script) + "})()")
        name = files[0][0]
        end = time.time() + 20
        while time.time() < end:
            if expect_error is not None and self.error():
                break
            if expect_error is None and self.status()["source"] == name:
                break
            time.sleep(0.1)
        if expect_error is not None:
            error = self.error()
            assert error.startswith(expect_error), f"dropping {name}: expected an error starting {expect_error!r}, got {error!r}"
            return error
        self.check_error(f"dropping {name}")
        assert self.status()["source"] == name, self.status()

    def hash_after(self, steps):
        """Pauses, starts the loaded scene over and steps it `steps` times in one go."""
        return self.b.evaluate(f"(() => {{ hairsim.pause(true); hairsim.reset(); return hairsim.runSteps({steps}); }})()")

    def realtime(self, seconds=REALTIME_SECONDS):
        """Runs in real time from a restarted clock; the page's numbers after `seconds`."""
        self.b.evaluate("hairsim.pause(false); hairsim.restartClock()")
        time.sleep(seconds)
        return self.status()

    def effect_box(self, name):
        return (
            "[...document.querySelectorAll('#effects label')].find((l) => l.firstChild.nextSibling.textContent.trim() === "
            + json.dumps(name) + ").querySelector('input')"
        )

    def click_effect(self, name):
        self.b.evaluate(f"{self.effect_box(name)}.click()")

    def solver(self, solver):
        self.b.evaluate(f"document.querySelector('input[name=solver][value={solver}]').click()")
        self.check_error(f"switching to {solver}")
        assert self.status()["solver"] == solver


def read_sample(samples):
    return open(os.path.join(samples, HAIR_FILE), "rb").read()


def check_hashes(binary, page, samples):
    for query, label in [("", "simd128"), ("?simd=0", "no SIMD")]:
        page.navigate(query)
        module = page.status()["module"]
        assert ("simd" in module) == (query == ""), f"{label}: the page runs {module}"
        scenes = HASH_SCENES if query == "" else HASH_SCENES[1:]
        for scene, steps in scenes:
            page.load(scene)
            page_hash = page.hash_after(steps)
            expected = native_hash(binary, scene, steps)
            print(f"  {label:8} {scene:14} {steps:5} steps: page {page_hash}, native {expected}")
            assert page_hash == expected, f"{scene} ({label}): the page's state hash differs from the native run"
        dropped = [((HAIR_FILE, read_sample(samples)), os.path.join(samples, HAIR_FILE), 100),
                   ((os.path.basename(HELD_SCENE), open(HELD_SCENE, "rb").read()), HELD_SCENE, 1500)]
        for file, path, steps in dropped:
            page.drop([file])
            page_hash = page.hash_after(steps)
            expected = native_hash(binary, path, steps)
            print(f"  {label:8} {file[0]:14} {steps:5} steps: page {page_hash}, native {expected} (dropped on the page)")
            assert page_hash == expected, f"{file[0]} ({label}): the page's state hash differs from the native run"
    page.navigate()


# (label, how to load it, solver, steps) whose stepping cost the page and `hairsim run` compare.
SPEED_CASES = [("head-2", "head-2", "rod", 1000), ("head-2", "head-2", "dftl", 1000), (HAIR_FILE, HAIR_FILE, "dftl", 300)]
SPEED_SCENE = """format = 1
name = "{name}-{solver}"
{base}
"""


def native_cost(binary, scene, steps):
    out = subprocess.run(
        [binary, "run", scene, "--steps", str(steps), "--json", "--threads", "1"],
        check=True, capture_output=True, text=True,
    ).stdout
    return 1000 * json.loads(out)["ms_per_step"]


def check_speed(binary, page, samples, rounds):
    """The page's stepping cost (median over batches of steps, in µs per step) against
    `hairsim run --threads 1`'s (its median step), the two alternated `rounds` times."""
    rows = []
    for label, scene, solver, steps in SPEED_CASES:
        native_scene = scene
        if scene == HAIR_FILE:
            page.drop([(HAIR_FILE, read_sample(samples))])
            native_scene = os.path.join(samples, HAIR_FILE)
        else:
            page.load(scene)
        if page.status()["solver"] != solver:
            page.solver(solver)
            # The native run of the other solver: the scene file the page runs.
            native_scene = os.path.join(tempfile.gettempdir(), f"hairsim-speed-{os.getpid()}-{label}-{solver}.toml")
            open(native_scene, "w").write(page.b.evaluate("hairsim.sceneToml()"))
        natives, pages = [], []
        for _ in range(rounds):
            natives.append(native_cost(binary, native_scene, steps))
            pages.append(page.b.evaluate(f"hairsim.pause(true), hairsim.benchmark({steps})"))
        page_us = sorted(pages)[len(pages) // 2]
        native_us = sorted(natives)[len(natives) // 2]
        print(f"  {label:16} {solver:5} page {page_us:8.1f} us/step, native --threads 1 "
              f"{native_us:8.1f} us/step, page / native {page_us / native_us:5.2f}")
        rows.append((label, solver, page_us, native_us))
    return rows


EFFECT_BOXES = """(() => {
  // Each box found anew: a switch redraws the panel.
  const label = (name) => [...document.querySelectorAll('#effects label')]
    .find((l) => l.firstChild.nextSibling.textContent.trim() === name);
  const names = [...document.querySelectorAll('#effects label')].map((l) => l.firstChild.nextSibling.textContent.trim());
  return names.map((name) => {
    const status = hairsim.status();
    const box = label(name).querySelector('input');
    const before = status.effects.includes(name);
    const row = { name, reason: status.unusable[name] ?? null, disabled: box.disabled, shown: label(name).textContent,
                  switched: null, back: null, error: '' };
    if (!box.disabled) {
      box.click();
      row.switched = hairsim.status().effects.includes(name) !== before;
      row.error = hairsim.error();
      label(name).querySelector('input').click();
      row.back = hairsim.status().effects.includes(name) === before;
    }
    return row;
  });
})()"""


def check_effect_boxes(page):
    """Every effect box, on a rod scene and a DFTL scene: a usable one switches the effect
    and back, an unusable one is disabled and says why."""
    for scene in ["firmware", "head-2"]:
        page.load(scene)
        for solver in ["rod", "dftl"]:
            page.solver(solver)
            page.b.evaluate("hairsim.pause(true)")
            rows = page.b.evaluate(EFFECT_BOXES)
            assert sorted(r["name"] for r in rows) == sorted(EFFECTS), rows
            for r in rows:
                what = f"{scene} {solver} {r['name']}"
                assert r["disabled"] == bool(r["reason"]), f"{what}: disabled {r['disabled']}, reason {r['reason']!r}"
                if r["disabled"]:
                    assert r["reason"] in r["shown"], f"{what}: the reason is not shown: {r['shown']!r}"
                else:
                    assert not r["error"], f"{what}: {r['error']}"
                    assert r["switched"] and r["back"], f"{what} did not switch and back: {r}"
            switched = sorted(r["name"] for r in rows if not r["disabled"])
            refused = sorted(r["name"] for r in rows if r["disabled"])
            print(f"  {scene:9} {solver:5}: switched {', '.join(switched)}; disabled with a reason: {', '.join(refused)}")


EFFECTS = ["gravity", "drag", "bending", "twist", "inextensibility", "collisions", "shape", "wind", "grabs", "hair-hair"]

GOOD_SCENE = """format = 1
name = "dropped-with-its-hair"
solver = "dftl"
dt = 0.001
steps = 1000
effects = ["gravity", "drag", "inextensibility", "shape", "collisions"]
drag = 2.0e-7

[hair.file]
path = "hair/{hair}"

[[colliders]]
shape = "sphere"
centre = [0.0, 1.6, 0.0]
radius = 0.09
"""


def check_drops(page, samples):
    """Drops through real drop events: a malformed hair file (an error naming it; the old
    scene keeps running), a scene file with the hair file it names, and one without it."""
    page.load("firmware")
    page.b.evaluate("hairsim.pause(false)")
    before = page.status()
    error = page.drop([("forged.tfx", bytes(range(7, 47)))], expect_error="forged.tfx")
    time.sleep(0.3)
    after = page.status()
    assert after["source"] == before["source"] and after["steps"] > before["steps"], (before, after)
    print(f"  forged.tfx: {error!r}; {before['source']} still runs")
    scene = GOOD_SCENE.format(hair=HAIR_FILE).encode()
    page.drop([("with-hair.toml", scene), (HAIR_FILE, read_sample(samples))])
    status = page.status()
    selected = page.b.evaluate("document.getElementById('scene').selectedOptions[0].textContent")
    assert "with-hair.toml" in selected, f"the scene list shows {selected!r}"
    print(f"  with-hair.toml + {HAIR_FILE}: runs {status['strands']} strands; the scene list shows {selected!r}")
    error = page.drop([("alone.toml", scene)], expect_error="alone.toml")
    assert HAIR_FILE in error, error
    print(f"  alone.toml: {error!r}")
    page.b.evaluate("hairsim.pause(true)")


DRAG_SCENE, DRAG_STRAND, DRAG_NODE, DRAG_SETTLE_STEPS = "stand-1", 0, 10, 3000
DRAG_CM = [0.5, 1.0, 1.5, 2.0]


def vector(a, b):
    return [x - y for x, y in zip(a, b)]


def norm(v):
    return sum(x * x for x in v) ** 0.5


def pixels_per_cm(page, x, y):
    """Pixels per centimetre at the held node's depth, from a small diagonal move of the
    pointer pressed at (x, y), 7 pixels on each axis (the pointer is left there)."""
    start = page.status()["grab_target"]
    page.b.mouse("mouseMoved", x + 7, y - 7)
    return 7 * 2 ** 0.5 / (100 * norm(vector(page.status()["grab_target"], start)))


def check_drag(page):
    """Grabs a settled, hanging wisp of stand-1 10 cm below its root with the mouse and drags
    it up and sideways on the screen by 0.5, 1, 1.5 and 2 cm, holding each for 1 s of simulated
    time. (Further, the wisp folds over the hand and the force levels off; straight away from
    the root, an inextensible strand is soon pulled taut and the grab's spring stretches.) The
    page is paused and stepped by the test (`runSteps`), so the forces are the same bits on
    every machine; the mouse events go through the page's own handlers."""
    page.load(DRAG_SCENE)
    page.b.evaluate(f"hairsim.pause(true); hairsim.reset(); hairsim.runSteps({DRAG_SETTLE_STEPS})")
    x, y, _ = page.b.evaluate(f"hairsim.screen({DRAG_STRAND}, {DRAG_NODE})")
    page.b.mouse("mousePressed", x, y)
    first = page.status()
    assert first["grab"] == "held", f"pressing on a strand grabbed nothing: {first['grab']}"
    start = first["grab_target"]
    # Up and to the right on the screen, each axis 1/√2 of the drag.
    per_cm = pixels_per_cm(page, x, y) / 2 ** 0.5
    magnitudes = []
    for cm in DRAG_CM:
        page.b.mouse("mouseMoved", x + cm * per_cm, y - cm * per_cm)
        # 0.5 s to follow the hand, then the force every 10 steps for 0.5 s.
        page.b.evaluate("hairsim.runSteps(500)")
        forces = page.b.evaluate(
            "Array.from({length: 50}, () => { hairsim.runSteps(10); return hairsim.status().grab_force; })"
        )
        status = page.status()
        drag = vector(status["grab_target"], start)
        length = norm(drag)
        mean = [sum(f[i] for f in forces) / len(forces) for i in range(3)]
        along = sum(f * d for f, d in zip(mean, drag)) / length
        magnitude = norm(mean)
        print(f"  drag {100 * length:.1f} cm: mean force {magnitude:.3e} N,"
              f" {along / magnitude if magnitude else 0:.3f} of it along the drag, grab {status['grab']}")
        assert status["grab"] == "held", f"the grab let go: {status['grab']}"
        assert along > 0.5 * magnitude > 0, "the grab force does not point toward the target"
        magnitudes.append(magnitude)
    assert all(b > a for a, b in zip(magnitudes, magnitudes[1:])), f"the force does not grow: {magnitudes}"
    page.b.mouse("mouseReleased", x + DRAG_CM[-1] * per_cm, y - DRAG_CM[-1] * per_cm)
    after = page.status()
    assert after["grab_force"] == [0, 0, 0] and after["grab"] != "held", after
    print(f"  released: grab {after['grab']}, force {after['grab_force']}")


def check_dftl_drag(page, samples):
    """DFTL hair as a user meets it: sintel_hair.tfx dropped on the page (DFTL, shape on),
    settled, a strand pressed and the pointer moved 1.5 cm up and 1 cm sideways on the screen
    (the hand moves in the plane facing the camera through the node): the held node follows
    the hand (most of the way, within 2 mm after 0.3 s), the force is nonzero and plotted."""
    page.drop([(HAIR_FILE, read_sample(samples))])
    status = page.status()
    assert status["solver"] == "dftl", status["solver"]
    page.b.evaluate("hairsim.pause(true); hairsim.reset(); hairsim.runSteps(200)")
    x, y, _ = page.b.evaluate("hairsim.screen(0, 8)")
    page.b.mouse("mousePressed", x, y)
    held = page.status()
    assert held["grab"] == "held", f"pressing on a DFTL strand grabbed nothing: {held['grab']} ({page.error()})"
    strand, node = held["held"]["strand"], held["held"]["node"]
    before = held["held"]["position"]
    per_cm = pixels_per_cm(page, x, y)
    page.b.mouse("mouseMoved", x + 1.0 * per_cm, y - 1.5 * per_cm)
    page.b.evaluate("hairsim.runSteps(300)")
    time.sleep(0.3)
    status = page.status()
    now, target = status["held"]["position"], status["grab_target"]
    moved, lag = norm(vector(now, before)), norm(vector(now, target))
    force = norm(status["grab_force"])
    print(f"  {HAIR_FILE}: strand {strand} node {node} dragged {100 * norm(vector(target, before)):.1f} cm:"
          f" it moved {100 * moved:.2f} cm and is {1000 * lag:.2f} mm from the hand; force {force:.3e} N,"
          f" plotted {status['plotted']['samples']} samples up to {status['plotted']['max']:.3e} N, grab {status['grab']}")
    assert status["grab"] == "held", status["grab"]
    dragged = norm(vector(target, before))
    assert dragged > 0.005, f"the hand moved the target {100 * dragged:.2f} cm only"
    assert moved > 0.8 * dragged and lag < 0.002, "the strand does not follow the hand"
    assert force > 0 and status["plotted"]["max"] > 0, "no force shown"
    page.b.mouse("mouseReleased", x + 1.0 * per_cm, y - 1.5 * per_cm)
    assert page.status()["grab"] == "none"


def check_slip_and_regrab(page):
    """The mouse grab is coupled. Grabs the same wisp and pulls it straight down, 5 cm past its
    reach (a prescribed grab slipped there at once): it holds, the strand taut, with the
    spring's force K |x − T|. Pulled on down, it slips when that force passes its limit (drawn,
    marked on the force plot, a warning); a second press, without letting go, grabs it again."""
    page.load(DRAG_SCENE)
    page.b.evaluate(f"hairsim.pause(true); hairsim.reset(); hairsim.runSteps({DRAG_SETTLE_STEPS})")
    x, y, _ = page.b.evaluate(f"hairsim.screen({DRAG_STRAND}, {DRAG_NODE})")
    page.b.mouse("mousePressed", x, y)
    status = page.status()
    assert status["grab"] == "held"
    stiffness, limit = status["grab_coupling"][0], status["grab_limit"]
    # The arc length from node 1 (the head holds nodes 0 and 1) to the held node.
    nodes = [page.b.evaluate(f"hairsim.node({DRAG_STRAND}, {n})") for n in range(1, DRAG_NODE + 1)]
    reach = sum(norm(vector(b, a)) for a, b in zip(nodes, nodes[1:]))
    per_cm = pixels_per_cm(page, x, y)

    # Down and to the right on the screen: room for the 20 cm the spring stretches to its limit.
    direction = (0.8, 0.6)

    def point(pixels):
        return x + direction[0] * pixels, y + direction[1] * pixels

    def pull(pixels):
        """The pointer `pixels` along `direction`; how far past the reach it is, m."""
        page.b.mouse("mouseMoved", *point(pixels))
        return norm(vector(page.status()["grab_target"], nodes[0])) - reach

    # 5 cm past the reach: a bisection on the pointer's distance, never so far that the spring
    # would pass the force limit (K × 15 cm < 1 N) should the page step while it runs.
    low, high = 0.0, 15 * per_cm
    for _ in range(20):
        middle = (low + high) / 2
        low, high = (middle, high) if pull(middle) < 0.05 else (low, middle)
    past = pull(high)
    page.b.evaluate("hairsim.runSteps(1000)")
    status = page.status()
    stretch = norm(vector(status["held"]["position"], status["grab_target"]))
    force = norm(status["grab_force"])
    print(f"  {100 * past:.1f} cm past its reach ({100 * reach:.1f} cm of hair): grab {status['grab']},"
          f" the spring stretched {100 * stretch:.2f} cm, {force:.3f} N (K |x - T| = {stiffness * stretch:.3f} N)")
    assert status["grab"] == "held", f"past its reach, the coupled grab let go: {status['grab']}"
    assert stretch > 0.9 * past, f"the strand gave {stretch} m of {past} m"
    assert abs(force - stiffness * stretch) < 0.02 * force, f"{force} N against K |x - T| = {stiffness * stretch} N"
    # On, 1 cm every 0.1 s of simulated time, until the grab lets go.
    pixels = high
    while status["grab"] == "held":
        pixels += per_cm
        px, py = point(pixels)
        assert px < 1280 and py < 800, f"the grab held to the edge of the page: {status}"
        pull(pixels)
        page.b.evaluate("hairsim.runSteps(100)")
        status = page.status()
    slipped = wait_for(page, lambda s: s["slips"] >= 1 and any("slipped" in w for w in s["warnings"]), 5,
                       "the slip not marked on the force plot and warned")
    held = float(slipped["warnings"][-1].split("holding ")[1].split(" N")[0])
    print(f"  slipped {100 * (norm(vector(status['grab_target'], nodes[0])) - reach):.1f} cm past its reach,"
          f" holding {held:.3f} N (limit {limit} N, {limit / stiffness * 100:.0f} cm of spring)")
    assert status["grab"] == "slipped"
    assert 0.9 * limit <= held <= limit, f"slipped holding {held} N, limit {limit} N"
    # The second press (the other button: the first is still down) lands where the strand
    # now is.
    sx, sy, _ = page.b.evaluate(f"hairsim.screen({DRAG_STRAND}, {DRAG_NODE})")
    page.b.mouse("mouseMoved", sx, sy)
    page.b.mouse("mousePressed", sx, sy, button="right", buttons=3)
    again = page.status()
    assert again["grab"] == "held", f"a second press did not re-grab: {again['grab']}"
    page.b.mouse("mouseReleased", sx, sy, button="right", buttons=1)
    page.b.mouse("mouseReleased", sx, sy)
    print(f"  {slipped['warnings'][-1]!r}; a second press re-grabbed: {again['grab']}")


def wait_for(page, predicate, seconds, what):
    end = time.time() + seconds
    while time.time() < end:
        status = page.status()
        if predicate(status):
            return status
        time.sleep(0.1)
    raise AssertionError(f"{what} within {seconds} s: {page.status()}")


def check_stall_and_recovery(page):
    """The rod on head-2 with inextensibility unticked: the stretch and the roll-backs show as
    they happen, and after strands have been rolled back at every step for a second the page says
    it is stuck and offers reset. Ticked back on, the hair recovers: within a second no roll-back
    and no stretch past 1 %."""
    page.load("head-2")
    page.solver("rod")
    page.b.evaluate("hairsim.pause(false); hairsim.restartClock()")
    page.click_effect("inextensibility")
    stretched = wait_for(page, lambda s: any("stretched" in w for w in s["warnings"]), 10, "no stretch warning")
    stuck = wait_for(page, lambda s: s["stuck"], 15, "not stuck")
    shown = page.b.evaluate("document.getElementById('stuck').innerText")
    assert "reset" in shown, shown
    print(f"  inextensibility off: {'; '.join(stretched['warnings'])}; then: {shown.splitlines()[0]!r}")
    page.click_effect("inextensibility")
    page.check_error("inextensibility back on")
    time.sleep(1.0)
    page.b.evaluate("hairsim.restartClock()")
    time.sleep(1.0)
    status = page.status()
    assert not status["stuck"], "still stuck after inextensibility came back"
    assert status["report"]["rolled_back"] == 0 and status["report"]["max_stretch"] < 0.01, status["report"]
    assert not status["warnings"], f"warnings a second after recovery: {status['warnings']}"
    print(f"  back on: no warning, {status['report']['rolled_back']} rolled back, stretch {status['report']['max_stretch']:.1e}")
    page.b.evaluate("hairsim.pause(true)")


def check_time(page):
    """A 15 s stall (the page's clock moved 15 s on at once: what the next frame sees after a
    hidden tab or a long task) is dropped, not caught up: the lag stays within one frame and
    the page goes on in real time."""
    page.load("firmware")
    page.b.evaluate("hairsim.pause(false); hairsim.restartClock()")
    time.sleep(1.0)
    before = page.status()
    page.b.evaluate("hairsim.stall(15000)")
    time.sleep(0.3)
    stalled = page.status()
    assert stalled["dropped_s"] >= 14.5, f"the stall was not dropped: {stalled['dropped_s']} s"
    assert stalled["lag_s"] <= stalled["frame_s"] + 1e-9, f"lag {stalled['lag_s']} s carried, frame {stalled['frame_s']} s"
    time.sleep(1.5)
    after = page.status()
    simulated = after["time"] - stalled["time"]
    print(f"  15 s stall: {stalled['dropped_s']:.2f} s dropped, lag {1000 * stalled['lag_s']:.0f} ms;"
          f" the next 1.5 s of wall time ran {simulated:.2f} s (ratio {after['realtime_ratio']:.2f})")
    assert simulated < 1.5 * 1.1 + 0.1, f"the page caught up: {simulated} s simulated in 1.5 s"
    assert after["realtime_ratio"] > 0.9, after["realtime_ratio"]
    assert before["dropped_s"] < 0.5, before["dropped_s"]


def check_slow_motion(page):
    """A scene far too heavy for real time plays in slow motion, and the picture says so."""
    heavy = SWEEP_SCENE.format(solver="rod", leaders=1500, effects=json.dumps(SWEEP_EFFECTS["rod"]))
    page.drop([("too-heavy.toml", heavy.encode())])
    status = page.realtime(2.5)
    label = page.b.evaluate("document.getElementById('clock').textContent")
    print(f"  too-heavy.toml ({status['strands']} rod strands): real-time ratio {status['realtime_ratio']:.2f},"
          f" the picture says {label!r}, {status['dropped_s']:.1f} s dropped")
    assert label.startswith("slow motion ×"), label
    assert abs(float(label.split("×")[1]) - status["realtime_ratio"]) < 0.1, (label, status["realtime_ratio"])
    page.b.evaluate("hairsim.pause(true)")


def check_realtime(page, samples):
    rows = []

    def measure(label, solver=None):
        if solver:
            page.solver(solver)
        s = page.realtime()
        rows.append((label, s["solver"], s["realtime_ratio"], s["us_per_sim_ms"], s["strands"]))
        print(f"  {label:16} {s['solver']:5} {s['strands']:4} strands: real-time ratio {s['realtime_ratio']:.4f},"
              f" {s['us_per_sim_ms']:7.1f} us of compute per simulated ms, {s['steps_per_s']:5.0f} steps/s,"
              f" lag {1000 * s['lag_s']:4.0f} ms, {s['frames_per_s']:3.0f} frames/s drawn in {s['draw_ms_per_frame']:4.1f} ms each")
        return s

    page.load("firmware")
    firmware = measure("firmware")
    measure("firmware", "dftl")
    page.load("head-2")
    measure("head-2")
    measure("head-2", "dftl")
    page.drop([(HAIR_FILE, read_sample(samples))])
    measure(HAIR_FILE)
    assert firmware["realtime_ratio"] >= 0.99, f"firmware does not keep real time: {firmware['realtime_ratio']}"
    return rows


SWEEP_SCENE = """format = 1
name = "sweep-{solver}-{leaders}"
solver = "{solver}"
dt = 0.001
steps = 1000000
effects = {effects}
drag = 2.0e-7

[material]
youngs_modulus = 3.5e9
shear_modulus = 1.3e9
radius = 4.0e-5
density = 1300.0

[head.motion.shake]
axis = [0.0, 1.0, 0.0]
amplitude = 0.5
peak_speed = 10.0

[[colliders]]
shape = "sphere"
centre = [0.0, 0.0, 0.0]
radius = 0.1

[hair.scalp]
leaders = {leaders}
nodes = 30
length = 0.3
radius = 0.1
cap_angle = 1.2
followers = 0
"""
SWEEP_EFFECTS = {
    "rod": ["gravity", "drag", "bending", "twist", "inextensibility", "collisions"],
    "dftl": ["gravity", "drag", "inextensibility", "collisions", "shape"],
}


# Of each millisecond, the most the steps may take for the page to keep real time: the rest is
# for drawing and the page itself.
SWEEP_BUDGET_US = 900


def sweep(page, out):
    """For each solver, the most strands (30 nodes, 30 cm, at 1 kHz on head-2's shaking head)
    that the page steps in real time: the page's stepping cost (`hairsim.benchmark`, the median
    over batches, robust to a busy machine's hiccups, which the real-time ratio over a second is
    not) at most SWEEP_BUDGET_US per 1 ms step; doubling, then halving the gap to within 5 %.
    Writes the result to `out` as a table of benches/performance.py (see its docstring)."""
    load_start = os.getloadavg()[0]
    rows = []
    for solver, effects in SWEEP_EFFECTS.items():
        costs = {}

        def keeps_up(leaders):
            name = f"sweep-{solver}-{leaders}.toml"
            text = SWEEP_SCENE.format(solver=solver, leaders=leaders, effects=json.dumps(effects))
            page.drop([(name, text.encode())])
            costs[leaders] = page.b.evaluate("hairsim.pause(true), hairsim.benchmark(300)")
            print(f"  {solver:4} {leaders:5} strands: {costs[leaders]:8.1f} us per 1 ms step")
            return costs[leaders] <= SWEEP_BUDGET_US

        good, bad = 0, 8
        while keeps_up(bad):
            good, bad = bad, 2 * bad
        while bad - good > max(1, good // 20):
            middle = (good + bad) // 2
            if keeps_up(middle):
                good = middle
            else:
                bad = middle
        print(f"  {solver}: {good} strands keep real time, {bad} do not")
        label = {"rod": "rod", "dftl": "DFTL"}[solver]
        shown = ", ".join(e for e in effects if e not in ("gravity", "drag", "inextensibility"))
        rows.append([label, shown, str(good), f"{costs.get(good, 0):.0f}", str(bad), f"{costs[bad]:.0f}"])
    if out:
        status = page.status()
        cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name")), "?")
        module = "with `simd128`" if "simd" in status["module"] else "without SIMD"
        table = {
            "title": "Strands each solver keeps in real time in the browser",
            "after": "latency",
            "text": (
                "`hairsim view`'s page steps the strands in WebAssembly (the module "
                f"{module}, one thread, in the native harness's lanes) and draws them ({status['renderer']}). "
                f"A strand count keeps real time when stepping takes at most {SWEEP_BUDGET_US} µs of each "
                "1 ms step, the rest left for drawing: the median of the page's `hairsim.benchmark` over "
                "batches of at least 2 ms, 300 steps after a warm-up. The scene: 30-node, 30 cm strands "
                "on a head shaking at 10 rad/s, at 1 kHz, with gravity, drag, inextensibility and a 10 cm "
                "head sphere; counts doubled from 8, then bisected to within 5 %. "
                f"Machine: {cpu}, {os.cpu_count()} logical cores, headless Chromium; load average "
                f"(1 minute) {load_start:.1f} at the start and {os.getloadavg()[0]:.1f} at the end"
                + (" (other processes shared the machine: the counts may be low)."
                   if max(load_start, os.getloadavg()[0]) > 1 else ".")),
            "command": "python3 .ci/viewer-test.py target/release/hairsim --sweep --only strands"
                       " --sweep-out benches/tables/viewer.json",
            "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            "header": ["solver", "effects", "strands kept in real time", "µs per step",
                       "strands that fall behind", "µs per step"],
            "align": "llrrrr",
            "rows": rows,
        }
        json.dump(table, open(out, "w"), indent=1, ensure_ascii=False)
        open(out, "a").write("\n")
        print(f"  written to {out}")


def hair_pixels(page):
    data = base64.b64decode(page.b.send("Page.captureScreenshot", {"format": "png"})["data"])
    width, height, rows = png_pixels(data)
    hair = [p for row in rows for p in row if hair_coloured(p)]
    return data, width, height, hair


def screenshot(page, path):
    """head-2 hanging after 1.5 s, a strand grabbed: the followers drawn (many more hair pixels than the
    leaders alone) and shaded (many tones of hair); the picture for the README."""
    page.load("head-2")
    # 1.5 s of simulated time whatever the machine's speed: the hair has fallen.
    page.b.evaluate("hairsim.pause(true); hairsim.reset(); hairsim.runSteps(1500); document.getElementById('fit').click()")
    page.b.evaluate("document.getElementById('followers').click()")
    time.sleep(0.3)
    _, width, height, leaders = hair_pixels(page)
    page.b.evaluate("document.getElementById('followers').click()")
    page.b.evaluate("hairsim.pause(false)")
    # A hand on a strand, so that the picture shows the grab force's arrow and plot.
    x, y, _ = page.b.evaluate("hairsim.screen(12, 24)")
    page.b.mouse("mousePressed", x, y)
    for k in range(1, 11):
        page.b.mouse("mouseMoved", x + 4 * k, y - 2 * k)
        time.sleep(0.1)
    data, width, height, hair = hair_pixels(page)
    tones = {(r >> 3, g >> 3, b >> 3) for r, g, b in hair}
    print(f"  {path}: {width}x{height}, {len(hair)} hair pixels with the followers against {len(leaders)} with the"
          f" leaders only, {len(tones)} hair tones")
    page.b.mouse("mouseReleased", x + 40, y - 20)
    assert len(hair) > 0.02 * width * height, "the screenshot shows (almost) no hair"
    assert len(hair) > 3 * len(leaders), "the followers are not drawn"
    assert len(tones) >= 100, f"the hair is not shaded: {len(tones)} tones"
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    open(path, "wb").write(data)


def main():
    args = sys.argv[1:]
    binary = args[0]
    shot = args[args.index("--screenshot") + 1] if "--screenshot" in args else "docs/pictures/viewer.png"
    rounds = int(args[args.index("--speed") + 1]) if "--speed" in args else 1
    sweep_out = args[args.index("--sweep-out") + 1] if "--sweep-out" in args else None
    samples = os.environ.get("HAIRSIM_SAMPLES")
    if not samples:
        sys.exit("HAIRSIM_SAMPLES must name the sample hair files' folder")
    # --url: a page served elsewhere (the page's files and modules from a folder, to try a
    # change without building hairsim again).
    server = subprocess.Popen([binary, "view", "--port", "0"], stdout=subprocess.PIPE, text=True)
    browser = None
    started = time.time()
    try:
        url = server.stdout.readline().strip()
        if "--url" in args:
            url = args[args.index("--url") + 1]
        assert url.startswith("http://127.0.0.1:"), f"hairsim view served {url!r}"
        print(f"hairsim view serves {url}")
        browser = Browser()
        browser.open(url)
        page = Page(browser, url)
        page.wait_ready()
        checks = [
            ("same bits as the native run", lambda: check_hashes(binary, page, samples)),
            ("stepping cost, page against native (us per step, one thread)", lambda: check_speed(binary, page, samples, rounds)),
            ("every effect box", lambda: check_effect_boxes(page)),
            ("drops", lambda: check_drops(page, samples)),
            ("grab and drag with the mouse", lambda: check_drag(page)),
            ("grab and drag DFTL hair", lambda: check_dftl_drag(page, samples)),
            ("a grab that slips, re-grabbed", lambda: check_slip_and_regrab(page)),
            ("inextensibility off and on again", lambda: check_stall_and_recovery(page)),
            ("a 15 s stall, no catch-up", lambda: check_time(page)),
            ("slow motion", lambda: check_slow_motion(page)),
            (f"real time over {REALTIME_SECONDS:.0f} s", lambda: check_realtime(page, samples)),
        ]
        if "--sweep" in args:
            checks.append((f"strands that keep real time (steps within {SWEEP_BUDGET_US} us of each ms)", lambda: sweep(page, sweep_out)))
        checks.append(("screenshot", lambda: screenshot(page, shot)))
        only = args[args.index("--only") + 1].split(",") if "--only" in args else None
        for title, check in checks:
            if only and not any(o in title for o in only):
                continue
            start = time.time()
            print(f"{title}:")
            check()
            print(f"  ({time.time() - start:.1f} s)")
        errors = browser.errors()
        assert not errors, f"console errors: {errors}"
        print(f"no console errors; the viewer passed in {time.time() - started:.0f} s")
    finally:
        if browser:
            browser.close()
        server.kill()


if __name__ == "__main__":
    main()

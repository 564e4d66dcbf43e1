#!/usr/bin/env python3
"""Tests `hairsim view` in a real browser: Chromium (headless), driven over the DevTools
protocol through a pipe (no driver, no websocket library).

  - N steps of each scene in the page give the state hash of `hairsim run SCENE --steps N --json`
    (built-in scenes loaded from the page's list, the hair file dropped on the page);
  - the real-time ratio over 10 s, printed per scene and solver, asserted >= 0.99 for `firmware`;
  - a drag on a strand with synthetic mouse events: the grab force points toward the hand's
    target, grows as the drag lengthens, and is zero after release;
  - the solver and an effect switched from the panel;
  - no console error or uncaught exception;
  - a screenshot (docs/pictures/viewer.png) that shows hair-coloured pixels.

Usage: viewer-test.py HAIRSIM_BINARY [--screenshot FILE] [--sweep]
  --sweep: also find how many strands of each solver keep real time (for the docs; slow).
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
REALTIME_SECONDS = 10.0


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

    def mouse(self, kind, x, y):
        self.send(
            "Input.dispatchMouseEvent",
            {"type": kind, "x": x, "y": y, "button": "left", "buttons": 0 if kind == "mouseReleased" else 1, "clickCount": 1},
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
    """The page draws hair in #c8914a (anti-aliased over the #15171c background): warm, red
    above green above blue, and brighter than the background."""
    r, g, b = rgb
    return r > 90 and r > g + 15 and g > b + 10


class Page:
    def __init__(self, browser):
        self.b = browser

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

    def check_error(self, what):
        error = self.b.evaluate("window.hairsim.error()")
        assert not error, f"{what}: the page shows an error: {error}"

    def load(self, scene):
        """Loads a built-in scene as a user does: picks it in the page's list."""
        self.b.evaluate(
            f"(() => {{ const s = document.getElementById('scene'); s.value = {json.dumps(scene)};"
            " s.dispatchEvent(new Event('change')); })()"
        )
        self.check_error(f"loading {scene}")
        assert self.status()["scene"] == scene, self.status()

    def drop(self, name, data):
        """Drops a file on the page as a user does, and waits until it runs."""
        encoded = base64.b64encode(data).decode()
        self.b.evaluate(
            "(() => { const bytes = Uint8Array.from(atob(" + json.dumps(encoded) + "), (c) => c.charCodeAt(0));"
            " const transfer = new DataTransfer();"
            " transfer.items.add(new File([bytes], " + json.dumps(name) + "));"
            " document.getElementById('stage').dispatchEvent(new DragEvent('drop', {dataTransfer: transfer, bubbles: true, cancelable: true})); })()"
        )
        end = time.time() + 20
        while time.time() < end and self.status()["source"] != name:
            time.sleep(0.1)
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


def check_hashes(binary, page, samples):
    for scene, steps in HASH_SCENES:
        page.load(scene)
        page_hash = page.hash_after(steps)
        expected = native_hash(binary, scene, steps)
        print(f"  {scene:14} {steps:5} steps: page {page_hash}, native {expected}")
        assert page_hash == expected, f"{scene}: the page's state hash differs from the native run"
    path = os.path.join(samples, HAIR_FILE)
    page.drop(HAIR_FILE, open(path, "rb").read())
    page_hash = page.hash_after(100)
    expected = native_hash(binary, path, 100)
    print(f"  {HAIR_FILE:14}   100 steps: page {page_hash}, native {expected} (dropped on the page)")
    assert page_hash == expected, f"{HAIR_FILE}: the page's state hash differs from the native run"


def check_realtime(page, samples):
    rows = []

    def measure(label, solver=None):
        if solver:
            page.b.evaluate(f"document.querySelector('input[name=solver][value={solver}]').click()")
            page.check_error(f"{label}: switching to {solver}")
        s = page.realtime()
        rows.append((label, s["solver"], s["realtime_ratio"], s["us_per_sim_ms"], s["strands"]))
        print(f"  {label:16} {s['solver']:5} {s['strands']:4} strands: real-time ratio {s['realtime_ratio']:.4f},"
              f" {s['us_per_sim_ms']:7.1f} us of compute per simulated ms, {s['steps_per_s']:5.0f} steps/s,"
              f" lag {1000 * s['lag_s']:4.0f} ms, {s['frames_per_s']:3.0f} frames/s drawn in {s['draw_ms_per_frame']:4.1f} ms each")
        return s

    page.load("firmware")
    firmware = measure("firmware")
    measure("firmware", "dftl")
    page.load("firmware-dftl")
    measure("firmware-dftl")
    measure("firmware-dftl", "rod")
    page.load("head-2")
    measure("head-2")
    page.drop(HAIR_FILE, open(os.path.join(samples, HAIR_FILE), "rb").read())
    measure(HAIR_FILE)
    assert firmware["realtime_ratio"] >= 0.99, f"firmware does not keep real time: {firmware['realtime_ratio']}"
    return rows


DRAG_SCENE, DRAG_STRAND, DRAG_NODE, DRAG_SETTLE_STEPS = "stand-1", 0, 10, 3000
DRAG_CM = [0.5, 1.0, 1.5, 2.0]


def check_drag(page):
    """Grabs a settled, hanging wisp of stand-1 10 cm below its root with the mouse and drags
    it up and sideways on the screen by 0.5, 1, 1.5 and 2 cm, holding each for 1 s of simulated
    time. (Further, the wisp folds over the hand and the force levels off; straight away from
    the root, an inextensible strand is soon out of the hand's reach and slips.) The page is
    paused and stepped by the test (`runSteps`), so the forces are the same bits on every
    machine; the mouse events go through the page's own handlers."""
    page.load(DRAG_SCENE)
    page.b.evaluate(f"hairsim.pause(true); hairsim.reset(); hairsim.runSteps({DRAG_SETTLE_STEPS})")
    x, y, _ = page.b.evaluate(f"hairsim.screen({DRAG_STRAND}, {DRAG_NODE})")
    page.b.mouse("mousePressed", x, y)
    first = page.status()
    assert first["grab"] == "held", f"pressing on a strand grabbed nothing: {first['grab']}"
    start = first["grab_target"]
    # Pixels per centimetre at the grabbed node's depth, from a small diagonal move.
    page.b.mouse("mouseMoved", x + 7, y - 7)
    moved = [t - s for t, s in zip(page.status()["grab_target"], start)]
    pixels_per_cm = 7 / (100 * sum(d * d for d in moved) ** 0.5)
    magnitudes = []
    for cm in DRAG_CM:
        page.b.mouse("mouseMoved", x + cm * pixels_per_cm, y - cm * pixels_per_cm)
        # 0.5 s to follow the hand, then the force every 10 steps for 0.5 s.
        page.b.evaluate("hairsim.runSteps(500)")
        forces = page.b.evaluate(
            "Array.from({length: 50}, () => { hairsim.runSteps(10); return hairsim.status().grab_force; })"
        )
        status = page.status()
        drag = [t - s for t, s in zip(status["grab_target"], start)]
        length = sum(d * d for d in drag) ** 0.5
        mean = [sum(f[i] for f in forces) / len(forces) for i in range(3)]
        along = sum(f * d for f, d in zip(mean, drag)) / length
        magnitude = sum(f * f for f in mean) ** 0.5
        print(f"  drag {100 * length:.1f} cm: mean force {magnitude:.3e} N,"
              f" {along / magnitude if magnitude else 0:.3f} of it along the drag, grab {status['grab']}")
        assert status["grab"] == "held", f"the grab let go: {status['grab']}"
        assert along > 0.5 * magnitude > 0, "the grab force does not point toward the target"
        magnitudes.append(magnitude)
    assert all(b > a for a, b in zip(magnitudes, magnitudes[1:])), f"the force does not grow: {magnitudes}"
    page.b.mouse("mouseReleased", x + DRAG_CM[-1] * pixels_per_cm, y - DRAG_CM[-1] * pixels_per_cm)
    after = page.status()
    assert after["grab_force"] == [0, 0, 0] and after["grab"] != "held", after
    print(f"  released: grab {after['grab']}, force {after['grab_force']}")


def check_switches(page):
    page.load("firmware")
    page.b.evaluate("document.querySelector('input[name=solver][value=dftl]').click()")
    page.check_error("switching to DFTL")
    assert page.status()["solver"] == "dftl"
    box = "[...document.querySelectorAll('#effects label')].find((l) => l.textContent.trim() === 'gravity').querySelector('input')"
    page.b.evaluate(f"{box}.click()")
    page.check_error("switching gravity off")
    assert "gravity" not in page.status()["effects"], page.status()["effects"]
    page.b.evaluate(f"{box}.click()")
    assert "gravity" in page.status()["effects"]
    page.b.evaluate("document.querySelector('input[name=solver][value=rod]').click()")
    assert page.status()["solver"] == "rod"
    print("  solver rod -> dftl -> rod and gravity off -> on from the panel: no error")


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


def sweep(page):
    """For each solver, the most strands (30 nodes, 30 cm, at 1 kHz on head-2's shaking head)
    that keep real time: doubling, then halving the gap to within 5 %."""
    for solver, effects in SWEEP_EFFECTS.items():
        def keeps_up(leaders):
            name = f"sweep-{solver}-{leaders}.toml"
            text = SWEEP_SCENE.format(solver=solver, leaders=leaders, effects=json.dumps(effects))
            page.drop(name, text.encode())
            s = page.realtime()
            print(f"  {solver:4} {leaders:5} strands: real-time ratio {s['realtime_ratio']:.4f},"
                  f" {s['us_per_sim_ms']:8.1f} us per simulated ms")
            return s["realtime_ratio"] >= 0.99

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


def screenshot(page, path):
    page.load("head-2")
    page.b.evaluate("hairsim.pause(false); hairsim.restartClock()")
    time.sleep(2.0)
    page.b.evaluate("document.getElementById('fit').click()")
    # A hand on a strand, so that the picture shows the grab force's arrow and plot.
    x, y, _ = page.b.evaluate("hairsim.screen(12, 24)")
    page.b.mouse("mousePressed", x, y)
    for k in range(1, 11):
        page.b.mouse("mouseMoved", x + 4 * k, y - 2 * k)
        time.sleep(0.1)
    data = base64.b64decode(page.b.send("Page.captureScreenshot", {"format": "png"})["data"])
    width, height, rows = png_pixels(data)
    hair = sum(hair_coloured(p) for row in rows for p in row)
    print(f"  {path}: {width}x{height}, {hair} hair-coloured pixels ({100 * hair / (width * height):.1f} %)")
    page.b.mouse("mouseReleased", x + 40, y - 20)
    assert hair > 0.005 * width * height, "the screenshot shows (almost) no hair"
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    open(path, "wb").write(data)


def main():
    args = sys.argv[1:]
    binary = args[0]
    shot = args[args.index("--screenshot") + 1] if "--screenshot" in args else "docs/pictures/viewer.png"
    samples = os.environ.get("HAIRSIM_SAMPLES")
    if not samples:
        sys.exit("HAIRSIM_SAMPLES must name the sample hair files' folder")
    server = subprocess.Popen([binary, "view", "--port", "0"], stdout=subprocess.PIPE, text=True)
    browser = None
    try:
        url = server.stdout.readline().strip()
        assert url.startswith("http://127.0.0.1:"), f"hairsim view printed {url!r}"
        print(f"hairsim view serves {url}")
        browser = Browser()
        browser.open(url)
        page = Page(browser)
        page.wait_ready()
        print("same bits as the native run:")
        check_hashes(binary, page, samples)
        print("the panel:")
        check_switches(page)
        print("grab and drag with the mouse:")
        check_drag(page)
        print(f"real time over {REALTIME_SECONDS:.0f} s:")
        check_realtime(page, samples)
        if "--sweep" in args:
            print(f"strands that keep real time (over {REALTIME_SECONDS:.0f} s each):")
            sweep(page)
        print("screenshot:")
        screenshot(page, shot)
        errors = browser.errors()
        assert not errors, f"console errors: {errors}"
        print("no console errors; the viewer passed")
    finally:
        if browser:
            browser.close()
        server.kill()


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""The viewer in a real browser (docs/viewer.md).

Runs config/paper_two_robots.yaml for 40 steps with `mrslam_launch --view` on this test's own
DDS domain (in realtime, 5 times faster than the clock: about 5 s, so that the page sees the
steps go by; in lockstep the 40 steps take under a second), drives headless Chromium through chromedriver (the WebDriver HTTP
protocol, standard library only) and checks what a person sees: the step counter advances while
the run goes; the robots are drawn where the run put them (the evaluator's tracks.csv in r1's
frame, its TUM trajectories in r2's frame); a click on the frame selector switches the frame and
moves the drawing; the drawn robots have their colour on the canvas; and `mrslam_view --run`
replays the finished run, where dragging the slider shows an earlier step, again where the run
put it. Saves a screenshot of the live view. Exits 77 (skipped) only when Chromium cannot start.
"""
import argparse
import base64
import json
import math
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

SKIP = 77
DOMAIN = 140  # this test's own DDS domain
STEPS = 40
ROBOT_COLORS = {"r1": (0xd6, 0x27, 0x28), "r2": (0x1f, 0x77, 0xb4)}  # view.js COLORS
TOLERANCE_M = 2e-3  # the outputs keep 4 decimals, the view 6 significant digits


class Skip(Exception):
    pass


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_until(predicate, timeout_s, what):
    """Polls predicate every 50 ms until it returns a true value, which it returns."""
    deadline = time.monotonic() + timeout_s
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        time.sleep(0.05)


def http_json(method, url, body=None, timeout_s=30):
    data = None if body is None else json.dumps(body).encode()
    request = urllib.request.Request(url, data=data, method=method, headers={"Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(request, timeout=timeout_s) as response:
            return json.loads(response.read() or b"null")
    except urllib.error.HTTPError as error:
        return json.loads(error.read() or b"null")


class WebDriver:
    """The few WebDriver commands this test needs (W3C protocol over HTTP)."""

    def __init__(self, port):
        self.base = f"http://127.0.0.1:{port}"
        self.session = None

    def call(self, method, path, body=None):
        reply = http_json(method, f"{self.base}/session/{self.session}{path}", body)
        value = reply.get("value") if isinstance(reply, dict) else None
        if isinstance(value, dict) and "error" in value:
            raise AssertionError(f"WebDriver {method} {path}: {value['error']}: {value.get('message', '')[:300]}")
        return value

    def start(self, user_data_dir):
        args = ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=1280,860",
                "--force-device-scale-factor=1", f"--user-data-dir={user_data_dir}", "--no-first-run"]
        reply = http_json("POST", f"{self.base}/session", {
            "capabilities": {"alwaysMatch": {"goog:chromeOptions": {"binary": shutil.which("chromium"), "args": args}}}})
        value = reply.get("value", {}) if isinstance(reply, dict) else {}
        if "sessionId" not in value:
            raise Skip(f"Chromium cannot start: {value.get('message', reply)}"[:400])
        self.session = value["sessionId"]

    def quit(self):
        if self.session is not None:
            http_json("DELETE", f"{self.base}/session/{self.session}")
            self.session = None

    def get(self, url):
        self.call("POST", "/url", {"url": url})

    def js(self, script, *args):
        return self.call("POST", "/execute/sync", {"script": script, "args": list(args)})

    def element(self, css):
        value = self.call("POST", "/element", {"using": "css selector", "value": css})
        return next(iter(value.values()))

    def click(self, css):
        self.call("POST", f"/element/{self.element(css)}/click", {})

    def rect(self, css):
        return self.call("GET", f"/element/{self.element(css)}/rect")

    def drag(self, start, end):
        """A real mouse drag from start to end (viewport pixels)."""
        steps = [{"type": "pointerMove", "duration": 0, "x": int(start[0]), "y": int(start[1])},
                 {"type": "pointerDown", "button": 0},
                 {"type": "pointerMove", "duration": 200, "x": int(end[0]), "y": int(end[1])},
                 {"type": "pointerUp", "button": 0}]
        self.call("POST", "/actions", {"actions": [{"type": "pointer", "id": "mouse",
                                                    "parameters": {"pointerType": "mouse"}, "actions": steps}]})

    def screenshot(self, path):
        with open(path, "wb") as out:
            out.write(base64.b64decode(self.call("GET", "/screenshot")))


class Processes:
    """The processes this test starts, each in a process group of its own; all are ended at the end."""

    def __init__(self):
        self.started = []

    def start(self, argv, log_path):
        log = open(log_path, "w")
        process = subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                   start_new_session=True)
        log.close()
        self.started.append(process)
        return process

    def end_all(self):
        for process in reversed(self.started):
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGTERM)
                try:
                    process.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    os.killpg(process.pid, signal.SIGKILL)
                    process.wait()

    def none_left(self):
        """True when no process of any group this test started still exists."""
        for process in self.started:
            try:
                os.killpg(process.pid, 0)
                return False
            except ProcessLookupError:
                pass
        return True


def page_state(driver):
    return driver.js("return window.mrslamView ? {mode: mrslamView.mode, step: mrslamView.step, frame: mrslamView.frame,"
                     " drawn: mrslamView.drawn, stepText: document.getElementById('step').textContent} : null;")


def read_tracks(path):
    """tracks.csv: (step, robot, kind) -> (x, y) in r1's frame G1."""
    tracks = {}
    with open(path) as f:
        next(f)
        for line in f:
            step, robot, kind, _, x, y = line.strip().split(",")
            if kind in ("truth_robot", "estimate_robot"):
                tracks[(int(step), robot, kind.split("_")[0])] = (float(x), float(y))
    return tracks


def read_tum(path, time_s):
    """The (x, y) of a TUM trajectory at time_s."""
    with open(path) as f:
        for line in f:
            values = [float(v) for v in line.split()]
            if abs(values[0] - time_s) < 1e-4:
                return values[1], values[2]
    raise AssertionError(f"{path} has no pose at t = {time_s}")


def expect_near(drawn, expected, what):
    distance = math.hypot(drawn["x"] - expected[0], drawn["y"] - expected[1])
    assert distance < TOLERANCE_M, f"{what}: drawn at ({drawn['x']:.4f}, {drawn['y']:.4f}), the run has " \
                                   f"({expected[0]:.4f}, {expected[1]:.4f})"


def select_frame(driver, frame):
    driver.click(f"#frame option[value='{frame}']")
    wait_until(lambda: page_state(driver)["frame"] == frame, 5, f"the page to switch to frame {frame}")
    return page_state(driver)


def expect_in_r1_frame(driver, tracks):
    """Selects r1's frame by a click; every robot's truth and estimate as tracks.csv has them."""
    state = select_frame(driver, "r1")
    step = state["step"]
    for robot in ("r1", "r2"):
        for kind in ("truth", "estimate"):
            expect_near(state["drawn"][robot][kind], tracks[(step, robot, kind)], f"{robot} {kind} at step {step}")
    return state


def expect_robot_colors(driver, state):
    """The canvas pixel under each robot's drawn estimate has the robot's colour."""
    for robot, color in ROBOT_COLORS.items():
        e = state["drawn"][robot]["estimate"]
        pixel = driver.js("const c = document.getElementById('map').getContext('2d');"
                          "return Array.from(c.getImageData(arguments[0], arguments[1], 1, 1).data);",
                          round(e["px"]), round(e["py"]))
        assert tuple(pixel[:3]) == color, f"{robot}: canvas pixel {pixel} at ({e['px']:.0f}, {e['py']:.0f})"


def check_live(driver, processes, args, run_dir, tmp):
    view_port = free_port()
    launcher = processes.start(
        [f"{args.bin}/mrslam_launch", "--scenario", f"{args.source}/config/paper_two_robots.yaml", "--set",
         f"run.steps={STEPS}", "--set", "run.mode=realtime", "--set", "run.realtime_factor=5", "--out", run_dir, "--domain", str(DOMAIN), "--view", str(view_port), "--no-plots"],
        f"{tmp}/launch.log")
    url = f"http://127.0.0.1:{view_port}/"

    def viewer_up():
        assert launcher.poll() is None, f"mrslam_launch ended early: {open(f'{tmp}/launch.log').read()}"
        try:
            return http_json("GET", url + "info", timeout_s=1)
        except (urllib.error.URLError, ConnectionError):
            return None

    wait_until(viewer_up, 30, "the viewer to serve")
    driver.get(url)
    first = int(wait_until(lambda: (page_state(driver) or {}).get("step") is not None and page_state(driver)["stepText"],
                           30, "the first live frame"))
    wait_until(lambda: int(page_state(driver)["stepText"]) > first, 60, f"the step counter to advance past {first}")
    assert launcher.wait(timeout=120) == 0, open(f"{tmp}/launch.log").read()
    state = wait_until(lambda: page_state(driver)["step"] == STEPS and page_state(driver), 10,
                       f"the page to show the last step {STEPS}")
    assert state["frame"] == "world" and state["stepText"] == str(STEPS), state
    driver.screenshot(args.screenshot)
    print(f"live: the step counter went from {first} to {STEPS}; screenshot {args.screenshot}")


def check_frames(driver, run_dir):
    tracks = read_tracks(f"{run_dir}/tracks.csv")
    in_r1 = expect_in_r1_frame(driver, tracks)
    expect_robot_colors(driver, in_r1)
    in_r2 = select_frame(driver, "r2")
    time_s = STEPS * 0.65
    for kind in ("truth", "estimate"):
        expect_near(in_r2["drawn"]["r2"][kind], read_tum(f"{run_dir}/trajectories/r2_{kind}.tum", time_s),
                    f"r2 {kind} in r2's frame")
    expect_robot_colors(driver, in_r2)
    moved = math.hypot(in_r1["drawn"]["r1"]["estimate"]["px"] - in_r2["drawn"]["r1"]["estimate"]["px"],
                       in_r1["drawn"]["r1"]["estimate"]["py"] - in_r2["drawn"]["r1"]["estimate"]["py"])
    assert moved > 20, f"switching to r2's frame moved r1's drawing by {moved:.1f} px only"
    print(f"frames: r1's frame matches tracks.csv, r2's frame the TUM files; r1 moved {moved:.0f} px")


def check_replay(driver, processes, args, run_dir, tmp):
    viewer = processes.start([f"{args.bin}/mrslam_view", "--run", run_dir, "--port", "0"], f"{tmp}/replay.log")
    address = wait_until(lambda: re.search(r"serving (http://127\.0\.0\.1:\d+/)", open(f"{tmp}/replay.log").read()),
                         20, "the replay viewer's address").group(1)
    driver.get(address)
    wait_until(lambda: (page_state(driver) or {}).get("step") == STEPS, 20, "the replay at its last step")
    slider = driver.rect("#slider")
    y = slider["y"] + slider["height"] / 2
    driver.drag((slider["x"] + slider["width"] - 6, y), (slider["x"] + slider["width"] * 0.3, y))
    state = wait_until(lambda: 0 < page_state(driver)["step"] < STEPS and page_state(driver), 10,
                       "the slider to show an earlier step")
    assert state["stepText"] == str(state["step"]), state
    state = expect_in_r1_frame(driver, read_tracks(f"{run_dir}/tracks.csv"))
    print(f"replay: the slider dragged to step {state['step']}, drawn where the run put the robots")


def run(args):
    for tool in ("chromium", "chromedriver"):
        if shutil.which(tool) is None:
            raise Skip(f"{tool} is not installed (scripts/setup.sh installs it)")
    tmp = tempfile.mkdtemp(prefix="mrslam-live-view-")
    shm_before = {n for n in os.listdir("/dev/shm") if "chrom" in n}
    processes = Processes()
    driver_port = free_port()
    processes.start(["chromedriver", f"--port={driver_port}"], f"{tmp}/chromedriver.log")
    driver = WebDriver(driver_port)
    ok = False
    try:
        wait_until(lambda: _ready(driver_port), 20, "chromedriver")
        driver.start(f"{tmp}/chromium-profile")
        run_dir = f"{tmp}/run"
        check_live(driver, processes, args, run_dir, tmp)
        check_frames(driver, run_dir)
        check_replay(driver, processes, args, run_dir, tmp)
        ok = True
    finally:
        driver.quit()
        processes.end_all()
        try:  # Chromium's processes end shortly after chromedriver's
            left = wait_until(processes.none_left, 10, "every process this test started to end")
        except AssertionError:
            left = False
        shm_left = {n for n in os.listdir("/dev/shm") if "chrom" in n} - shm_before
        if ok and left and not shm_left:
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            print(f"kept {tmp} for its logs", file=sys.stderr)
    assert left, "a process this test started is still running"
    assert not shm_left, f"left in /dev/shm: {sorted(shm_left)}"


def _ready(port):
    try:
        return http_json("GET", f"http://127.0.0.1:{port}/status", timeout_s=1).get("value", {}).get("ready")
    except (urllib.error.URLError, ConnectionError):
        return False


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bin", required=True, help="folder of the executables (build/bin)")
    parser.add_argument("--source", required=True, help="the source tree (config/)")
    parser.add_argument("--screenshot", required=True, help="where to save the live view's screenshot")
    args = parser.parse_args()
    started = time.monotonic()
    try:
        run(args)
    except Skip as skip:
        print(f"SKIPPED: {skip}")
        return SKIP
    print(f"passed in {time.monotonic() - started:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The node's CPU share with and without the web page, and with a browser attached (prints figures; not a test).

    .venv/bin/python benchmarks/web_cpu.py                 # 3 x 3 runs of 10 s
    .venv/bin/python benchmarks/web_cpu.py --seconds 5 --repeats 1

The same run three ways, interleaved, in one invocation (the baseline measured beside the others):
``free_tumble`` at real-time factor 1 with ``rates.state`` raised to 200 Hz (many states to drop),
(a) without a page, (b) with ``web:=127.0.0.1:0`` and nobody watching, (c) with headless Chromium
showing the page. Figures: the node process's CPU time (user + system, from /proc) over the wall
time of the measured window (after start-up), as a share of one core; and, in (c), the browser's
own share (all its processes). The window opens once the node publishes (the start-up line) and
the browser, in (c), shows the status panel. Part 2 measures the page's own thread in this process
(less noisy): a simulator offering 200 states a second with no page, to a page nobody watches, and to
a page that sends every frame. Needs Debian's chromium (test/e2e/browser.py).
A loaded machine (other engineers' runs) makes every figure noisy: compare within one invocation.
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "test" / "e2e"))

from browser import CANDIDATES, Browser  # noqa: E402

URL = re.compile(r"web page http://(127\.0\.0\.1:\d+)/")
TICKS = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid: int) -> float:
    """User + system CPU time (s) of process ``pid``."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS


def tree(pid: int) -> list[int]:
    """``pid`` and its descendants."""
    found, todo = [], [pid]
    while todo:
        current = todo.pop()
        found.append(current)
        children = Path(f"/proc/{current}/task/{current}/children")
        if children.exists():
            todo += [int(c) for c in children.read_text().split()]
    return found


def one_run(mode: str, seconds: float, env: dict[str, str], log_dir: Path) -> tuple[float, float | None]:
    args = ["--ros-args", "-p", "scene:=free_tumble", "-p", "real_time_factor:=1.0", "-p", "rates.state:=200.0"]
    if mode != "none":
        args += ["-p", "web:=127.0.0.1:0"]
    log = log_dir / f"{mode}.log"
    with open(log, "wb") as out:
        node = subprocess.Popen(
            [sys.executable, "-m", "rigid_rot_sim.ros.node", *args], stdout=out, stderr=out, env=env
        )
    browser = None
    try:
        deadline = time.monotonic() + 60
        while "built:" not in log.read_text(errors="replace"):
            assert node.poll() is None and time.monotonic() < deadline, log.read_text()
            time.sleep(0.05)
        if mode == "browser":
            host = URL.search(log.read_text()).group(1)
            executable = next(path for name in CANDIDATES if (path := __import__("shutil").which(name)))
            browser = Browser(executable)
            browser.goto(f"http://{host}/")
            browser.until("document.body && /sim time/.test(document.body.innerText)", 60, "the status")
        browser_pids = tree(browser.process.pid) if browser else []
        node_cpu0, wall0 = cpu_seconds(node.pid), time.monotonic()
        browser_cpu0 = sum(cpu_seconds(p) for p in browser_pids)
        if browser:
            browser.pump(seconds)
        else:
            time.sleep(seconds)
        wall = time.monotonic() - wall0
        node_share = (cpu_seconds(node.pid) - node_cpu0) / wall
        browser_share = (sum(cpu_seconds(p) for p in browser_pids if Path(f"/proc/{p}").exists()) - browser_cpu0) / wall
        return node_share, (browser_share if browser else None)
    finally:
        if browser:
            browser.close()
        node.send_signal(2)
        node.wait(timeout=20)


def pump_alone(seconds: float) -> dict[str, float]:
    """Part 2, in this process (less noise than whole nodes): CPU share of offering 200 states a second
    with no page, to a page nobody watches, and to a page that sends every frame (as to a browser)."""
    import resource

    from rigid_rot_sim.run.body_view import body_view
    from rigid_rot_sim.run.simulator import Simulator
    from rigid_rot_sim.scene.scene import load_scene
    from rigid_rot_sim.share import resolve_scene
    from rigid_rot_sim.viewer import web

    def cpu() -> float:
        usage = resource.getrusage(resource.RUSAGE_SELF)
        return usage.ru_utime + usage.ru_stime

    scene = load_scene(resolve_scene("free_tumble"))
    sim = Simulator(scene, method="rk4")
    page = web.BodyPage("127.0.0.1", 0, body_view(scene), "benchmark")
    shares = {}
    try:
        for label, watched in (("no page", None), ("nobody watching", False), ("sending every frame", True)):
            pump = None if watched is None else web.FramePump(page, lambda f, r: "", watched=lambda w=watched: w)
            cpu0, wall0 = cpu(), time.monotonic()
            while time.monotonic() - wall0 < seconds:
                sim.advance(1)
                state = sim.snapshot()
                if pump is not None:
                    pump.offer(state)
                time.sleep(0.005)
            shares[label] = (cpu() - cpu0) / (time.monotonic() - wall0)
            if pump is not None:
                pump._stop.set()
                pump._thread.join()
    finally:
        page.close()
    return shares


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="measured window per run, s")
    parser.add_argument("--repeats", type=int, default=3, help="runs of each mode (interleaved)")
    options = parser.parse_args()
    env = dict(os.environ, ROS_DOMAIN_ID=str(os.getpid() % 100 + 1), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    modes = ("none", "page", "browser")
    shares: dict[str, list[float]] = {m: [] for m in modes}
    browser_shares: list[float] = []
    with tempfile.TemporaryDirectory() as log_dir:
        for _ in range(options.repeats):
            for mode in modes:
                node_share, browser_share = one_run(mode, options.seconds, env, Path(log_dir))
                shares[mode].append(node_share)
                if browser_share is not None:
                    browser_shares.append(browser_share)
    label = {
        "none": "node without a page",
        "page": "node with the page, no browser",
        "browser": "node with a browser attached",
    }
    base = statistics.median(shares["none"])
    print(f"free_tumble, rtf 1, ~/state at 200 Hz; {options.repeats} x {options.seconds:g} s per mode (median)")
    for mode in modes:
        median = statistics.median(shares[mode])
        spread = f"{100 * min(shares[mode]):.1f}..{100 * max(shares[mode]):.1f}"
        print(
            f"  {label[mode]:32s} {100 * median:6.1f} % of a core  ({median / base:4.2f}x the baseline; runs {spread})"
        )
    print(f"  {'the browser itself (Chromium)':32s} {100 * statistics.median(browser_shares):6.1f} % of a core")
    print(f"the page's thread alone, in one process, 200 states/s for {options.seconds:g} s each:")
    for label, share in pump_alone(options.seconds).items():
        print(f"  {label:32s} {100 * share:6.1f} % of a core")


if __name__ == "__main__":
    main()

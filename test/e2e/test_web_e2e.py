"""The body's web page in a real browser (headless Chromium over its DevTools protocol).

* a live run (``web`` parameter): the page draws a non-blank 3D canvas, the body turns (two
  screenshots a second apart differ), the status panel's sim time advances, and the page's pause
  button pauses the node (its ~/state stops);
* ``rigid-rot view BAG --web``: the same for a recording, with its own play / pause;
* the page fetches nothing off the host (every request the page makes goes to the server);
* a browser attached to a lockstep run (connecting, reloading, leaving mid-run) leaves the run
  digest equal to that of the same run without a page.

The screenshots are saved under ``out/web_e2e/`` (for the test log). In CI (``CI`` or
``RIGID_ROT_SIM_CI`` set) a browser that does not start fails these tests; elsewhere they skip.
"""

from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import viser  # noqa: F401  (the web extra: make setup installs it, so these tests always run)
from browser import start_browser
from e2e_helpers import WAIT

OUT = Path(__file__).resolve().parents[2] / "out" / "web_e2e"
URL = re.compile(r"web page http://(127\.0\.0\.1:\d+)/")
SIM_TIME = re.compile(r"sim time: ([0-9.]+) s")
PAGE_WAIT = 60.0  # s: the page's first frame on a loaded machine (software WebGL)


@pytest.fixture
def browser():
    page = start_browser()
    yield page
    page.close()


def _address_from(log, process_alive, pattern=URL, timeout: float = WAIT) -> str:
    deadline = time.monotonic() + timeout
    while (match := pattern.search(log())) is None:
        process_alive()
        assert time.monotonic() < deadline, f"no web page address in the log:\n{log()}"
        time.sleep(0.1)
    return match.group(1)


def _sim_time(browser) -> float:
    match = SIM_TIME.search(browser.text())
    assert match, f"no sim time in the status panel:\n{browser.text()}"
    return float(match.group(1))


def _open_page(browser, host: str) -> dict:
    browser.goto(f"http://{host}/")
    browser.until("document.body && /sim time: [0-9.]+ s/.test(document.body.innerText)", PAGE_WAIT, "the status")
    return browser.canvas_box()


def _check_the_body_turns(browser, box: dict, name: str) -> None:
    """A non-blank canvas whose picture changes within a second; the status panel's sim time advances."""
    t0 = _sim_time(browser)
    first = browser.screenshot(OUT / f"{name}_1.png", box)
    browser.pump(1.0)
    second = browser.screenshot(OUT / f"{name}_2.png", box)
    t1 = _sim_time(browser)
    assert t1 > t0, f"the status panel's sim time did not advance ({t0} -> {t1})"
    rgb = first[..., :3]
    assert rgb.std() > 0.02, "the 3D canvas is blank"
    # the omega arrow (orange: red high, blue low) is drawn
    assert np.count_nonzero((rgb[..., 0] > 0.8) & (rgb[..., 2] < 0.35) & (rgb[..., 1] > 0.3)) > 20
    changed = np.abs(first[..., :3] - second[..., :3]).max(axis=-1) > 0.05
    assert np.count_nonzero(changed) > 100, "two screenshots a second apart are the same: the body does not turn"


def test_live_page_turns_with_the_run_and_pauses_the_node(launch_node, collector, browser):
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    from rigid_rot_msgs.msg import RigidBodyState

    node = launch_node("--ros-args", "-p", "scene:=free_tumble", "-p", "web:=127.0.0.1:0")
    host = _address_from(node.log, node.check_alive)
    stamps: list[int] = []
    collector.node.create_subscription(
        RigidBodyState,
        "/rigid_rot_sim/state",
        lambda m: stamps.append(m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec),
        QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE),
    )
    box = _open_page(browser, host)
    _check_the_body_turns(browser, box, "live")
    collector.spin_until(lambda: len(stamps) > 5, WAIT, node, "~/state")
    # the page's pause button calls the node's ~/pause: the status panel says so, ~/state stops
    browser.click_button("Pause")
    browser.until("/pause: ok/.test(document.body.innerText)", WAIT, "the reply to pause")
    browser.until("/\\(paused\\)/.test(document.body.innerText)", WAIT, "the paused run")
    deadline = time.monotonic() + 0.3
    while time.monotonic() < deadline:  # states published before the pause may still be on their way
        collector.executor.spin_once(timeout_sec=0.05)
    paused_at = max(stamps)
    deadline = time.monotonic() + 1.5
    while time.monotonic() < deadline:
        collector.executor.spin_once(timeout_sec=0.05)
    assert max(stamps) == paused_at, "~/state went on after the page's pause"
    t_paused = _sim_time(browser)
    browser.pump(0.5)
    assert _sim_time(browser) == t_paused
    browser.click_button("Resume")
    collector.spin_until(lambda: max(stamps) > paused_at, WAIT, node, "~/state after resume")
    assert browser.foreign_requests(host) == [], "the page fetched something off the host"
    assert any(host in url for url in browser.requests)  # the log did record the page's own requests
    node.check_alive()
    assert "web page: update failed" not in node.log()


def test_view_plays_a_recording_in_the_browser(tmp_path, browser):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "recording"))
    from test_resim import record_like_the_node

    bag = tmp_path / "run.mcap"
    record_like_the_node(bag, "free_tumble", 8000, 10, {}, method="rk4")  # 8 s of sim time: 16 s at half speed
    command = [
        str(Path(sys.executable).parent / "rigid-rot"),
        "view",
        str(bag),
        "--web",
        "127.0.0.1:0",
        "--speed",
        "0.5",
    ]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines: list[str] = []
    try:
        line = process.stdout.readline()
        lines.append(line)
        match = re.search(r"http://(127\.0\.0\.1:\d+)/", line)
        assert match, line
        host = match.group(1)
        box = _open_page(browser, host)
        _check_the_body_turns(browser, box, "recording")
        assert "playing at 0.5x" in browser.text(), browser.text()
        browser.click_button("Pause")
        browser.until("/paused at/.test(document.body.innerText)", WAIT, "the paused playback")
        t_paused = _sim_time(browser)
        browser.pump(0.5)
        assert _sim_time(browser) == t_paused
        browser.click_button("Play")
        browser.until(f"!/sim time: {t_paused:.3f} s/.test(document.body.innerText)", WAIT, "playback again")
        assert browser.foreign_requests(host) == [], "the page fetched something off the host"
    finally:
        process.send_signal(2)
        out, _ = process.communicate(timeout=20)
        lines.append(out)
    assert process.returncode == 0, "".join(lines)
    assert "update failed" not in "".join(lines)


# -- a browser on a lockstep run changes no bit ---------------------------------------------------

NAMESPACE = "/web_e2e"
NODE = f"{NAMESPACE}/rigid_rot_sim"
DURATION = 2.0  # s of sim time: 100 turns of 0.02 s


def _lockstep_digest(launch_node, collector, browser=None) -> int:
    """One lockstep run of closed_loop_lockstep with the shipped controller; the digest of its last state."""
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from std_srvs.srv import SetBool

    from rigid_rot_msgs.msg import RigidBodyState

    state, torque = f"{NODE}/state", f"{NODE}/torque"
    controller = launch_node(
        "--ros-args",
        "-p",
        "target:=[0.0, 0.0, 0.5, 0.8660254037844386]",
        "-p",
        f"state_topic:={state}",
        "-p",
        f"torque_topic:={torque}",
        name="controller",
        module="rigid_rot_sim.ros.controller",
    )
    args = ["--ros-args", "-r", f"__ns:={NAMESPACE}", "-p", "scene:=closed_loop_lockstep"]
    args += ["-p", f"duration:={DURATION}", "-p", "start_paused:=true"]
    if browser is not None:
        args += ["-p", "web:=127.0.0.1:0"]
    node = launch_node(*args, name="sim")
    last: dict[int, int] = {}
    subscription = collector.node.create_subscription(
        RigidBodyState,
        state,
        lambda m: last.__setitem__(m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec, m.digest),
        QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE),
    )
    collector.spin_until(
        lambda: collector.node.count_subscribers(torque) >= 1 and collector.node.count_publishers(torque) >= 1,
        WAIT,
        node,
        "the loop's graph",
    )
    if browser is not None:  # a browser connects, disconnects and connects again (a reload) before the run goes
        host = _address_from(node.log, node.check_alive)
        _open_page(browser, host)
        browser.call("Page.reload")
        browser.until("document.body && /sim time/.test(document.body.innerText)", PAGE_WAIT, "the reloaded page")
    reply = collector.call(SetBool, f"{NODE}/pause", SetBool.Request(data=False), process=node, idempotent=True)
    assert reply.success, reply.message
    if browser is not None:  # ... and leaves while it runs
        browser.goto("about:blank")
    end = round(DURATION * 1e9)
    collector.spin_until(lambda: end in last, 120.0, node, "the last state")
    assert node.process.wait(timeout=30) == 0, node.log()
    controller.stop()
    collector.node.destroy_subscription(subscription)
    assert "LOCKSTEP on" in node.log()
    if browser is not None:
        assert "web page http://" in node.log()
    return last[end]


def test_a_browser_on_a_lockstep_run_leaves_the_digest_equal(launch_node, collector, browser):
    with_page = _lockstep_digest(launch_node, collector, browser)
    without = _lockstep_digest(launch_node, collector)
    assert with_page == without != 0

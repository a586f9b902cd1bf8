"""The web page's drawing and pace, without a browser (the browser tests: test/e2e/test_web_e2e.py).

* the wheels and the trail come from the one drawing (run/body_view.py): discs on the wheels'
  axes outside the box, the trail's point at the tip of the box's longest side;
* the pump shows at most MAX_RATE frames a second however fast states come, the latest one
  last, and taking a state costs the simulation an assignment;
* a recording's frames are its recorded states.
"""

from __future__ import annotations

import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import viser  # noqa: F401  (the web extra: make setup installs it, so these tests always run)
from scipy.spatial.transform import Rotation

from rigid_rot_sim.run.body_view import body_view
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import load_scene, parse_scene_text
from rigid_rot_sim.share import resolve_scene
from rigid_rot_sim.viewer import web

WHEEL_SCENE = """
body: {principal_moments: [120.0, 95.0, 140.0]}
initial: {angular_velocity: [0.1, 0.0, 0.2]}
actuators:
  reaction_wheels:
    - {name: a, axis: [1, 0, 0], inertia: 0.1, max_torque: 0.2, max_speed: 600.0}
    - {name: b, axis: [0, 0.6, 0.8], inertia: 0.1, max_torque: 0.2, max_speed: 600.0}
integrator: {method: gyrostat_rk4, dt: 0.01}
"""


def _corners(view) -> np.ndarray:
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    return view.box_center + Rotation.from_quat(view.box_orientation).apply(0.5 * signs * view.box_sides)


def test_wheels_are_discs_on_their_axes_outside_the_box():
    view = body_view(parse_scene_text(WHEEL_SCENE))
    assert len(view.wheel_axes) == len(view.wheel_centers) == 2
    np.testing.assert_allclose(view.wheel_axes[1], [0.0, 0.6, 0.8])
    for axis, center in zip(view.wheel_axes, view.wheel_centers, strict=True):
        offset = np.asarray(center) - view.box_center
        np.testing.assert_allclose(np.cross(offset, axis), 0.0, atol=1e-12)  # on the axis through the centre
        assert np.dot(offset, axis) > 0.0
        # just outside the box: every corner is behind the disc's inner face, the furthest one by half a thickness
        behind = (_corners(view) - np.asarray(center)) @ np.asarray(axis) + 0.5 * view.wheel_thickness
        assert behind.max() == pytest.approx(-0.5 * view.wheel_thickness, abs=1e-12)
        vertices, faces = web.disc_mesh(center, axis, view.wheel_radius, view.wheel_thickness)
        radial = vertices - np.asarray(center)
        radial -= np.outer(radial @ np.asarray(axis), axis)
        assert np.linalg.norm(radial, axis=1).max() == pytest.approx(view.wheel_radius, rel=1e-6)
        assert faces.max() < len(vertices)
    assert body_view(load_scene(resolve_scene("free_tumble"))).wheel_axes == ()


def test_the_trail_follows_the_tip_of_the_longest_side():
    scene = parse_scene_text(WHEEL_SCENE)
    view = body_view(scene)
    longest = int(np.argmax(view.box_sides))
    tip_body = view.box_center + Rotation.from_quat(view.box_orientation).apply(
        0.5 * view.box_sides[longest] * np.eye(3)[longest]
    )
    q = Rotation.from_rotvec([0.3, -0.2, 1.1]).as_quat()
    np.testing.assert_allclose(view.major_axis_tip(q), Rotation.from_quat(q).apply(tip_body), atol=1e-12)
    # principal moments 120, 95, 140: the smallest moment (the body's y) has the longest side
    assert abs(view.major_axis()[1]) == pytest.approx(0.5 * view.size)


def test_a_frame_is_the_snapshot():
    sim = Simulator(load_scene(resolve_scene("free_tumble")), method="rk4")
    sim.advance(10)
    snapshot = sim.snapshot()
    frame = web.Frame.of(snapshot)
    assert frame.t == snapshot.t and frame.digest == snapshot.digest != 0
    np.testing.assert_array_equal(frame.orientation, snapshot.orientation)
    np.testing.assert_array_equal(frame.momentum_world, snapshot.angular_momentum_world)


@pytest.fixture
def page():
    scene = load_scene(resolve_scene("free_tumble"))
    page = web.BodyPage("127.0.0.1", 0, body_view(scene), "test")
    yield page
    page.close()


def test_the_pump_shows_at_most_max_rate_frames_a_second_and_the_latest_last(page):
    sim = Simulator(load_scene(resolve_scene("free_tumble")), method="rk4")
    shown: list[float] = []
    pump = web.FramePump(page, lambda frame, rtf: shown.append(frame.t) or f"t {frame.t}", watched=lambda: True)
    try:
        start = time.monotonic()
        offered = 0
        while time.monotonic() - start < 1.5:  # states as fast as the simulator makes them
            sim.advance(1)
            pump.offer(sim.snapshot())
            offered += 1
        elapsed = time.monotonic() - start
        last = sim.snapshot()
        deadline = time.monotonic() + 10.0
        while not shown or shown[-1] != last.t:
            assert time.monotonic() < deadline, "the latest state was never shown"
            time.sleep(0.01)
    finally:
        pump.close()
    assert offered > 100 and pump.offered == offered
    assert pump.sent <= web.MAX_RATE * (elapsed + 0.5)  # frames dropped, never queued
    assert 3 <= pump.sent < offered
    assert shown == sorted(shown) and pump.failure is None


def test_offering_a_state_costs_an_assignment(page):
    pump = web.FramePump(page, lambda frame, rtf: "", watched=lambda: True)
    try:
        snapshot = Simulator(load_scene(resolve_scene("free_tumble")), method="rk4").snapshot()
        start = time.perf_counter()
        for _ in range(100_000):
            pump.offer(snapshot)
        per_offer = (time.perf_counter() - start) / 100_000
    finally:
        pump.close()
    assert per_offer < 20e-6  # a loaded 2-core machine: still far below a step's publishing


def test_a_stalled_page_does_not_stall_the_offers(page):
    """A page that takes long to update (a slow browser, a busy server) only delays the pump."""
    release = threading.Event()
    pump = web.FramePump(page, lambda frame, rtf: release.wait(5.0) and "", watched=lambda: True)
    try:
        snapshot = Simulator(load_scene(resolve_scene("free_tumble")), method="rk4").snapshot()
        deadline = time.monotonic() + 1.0
        pump.offer(snapshot)
        while pump.sent == 0 and time.monotonic() < deadline:
            time.sleep(0.01)
        start = time.perf_counter()
        for _ in range(10_000):
            pump.offer(snapshot)
        assert time.perf_counter() - start < 1.0
    finally:
        release.set()
        pump.close()


def test_a_recordings_frames_are_its_states(tmp_path):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "recording"))
    from test_resim import record_like_the_node

    from rigid_rot_sim.recording.reader import BagReader
    from rigid_rot_sim.viewer.web_playback import recorded_frames

    bag = tmp_path / "run.mcap"
    record_like_the_node(bag, "free_tumble", 200, 10, {}, method="rk4")
    scene, frames = recorded_frames(bag)
    assert scene.name == "free_tumble"
    states = list(BagReader(bag).messages(["/rigid_rot_sim/state"]))
    assert len(frames) == len(states) >= 20
    assert [round(f.t * 1e9) for f in frames] == [m.log_time_ns for m in states]
    assert frames[-1].digest != 0


def test_without_viser_the_run_goes_on_and_view_says_so_in_one_line(monkeypatch, tmp_path, capsys):
    from rigid_rot_sim.cli import main
    from rigid_rot_sim.ros import web_live

    monkeypatch.setitem(sys.modules, "viser", None)  # as if not installed: find_spec finds nothing
    assert not web_live.available()
    view = body_view(load_scene(resolve_scene("free_tumble")))
    live, words = web_live.start("127.0.0.1:0", None, None, view, "t")  # the node is not touched
    assert live is None and words == web.missing_line  # the start-up line lists it as left out
    assert main(["view", str(tmp_path / "missing.mcap"), "--web", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "viser is not installed (pip install rigid_rot_sim[web])" in err
    with pytest.raises(ValueError, match="web page address 'x:y'"):
        web_live.start("x:y", None, None, view, "t")


def test_a_host_that_is_not_ours_is_a_clear_error_not_a_hang():
    view = body_view(load_scene(resolve_scene("free_tumble")))
    start = time.monotonic()
    with pytest.raises(OSError, match="cannot listen on host '192.0.2.1'"):  # TEST-NET-1: never a local address
        web.BodyPage("192.0.2.1", 0, view, "t")
    assert time.monotonic() - start < 10.0


def test_run_web_becomes_the_nodes_web_parameter():
    from rigid_rot_sim.cli import build_parser
    from rigid_rot_sim.cli.run import node_arguments

    _, overrides = node_arguments(build_parser("run").parse_args(["run", "free_tumble", "--web", "127.0.0.1:8080"]))
    assert {o.name: o.value for o in overrides}["web"] == "127.0.0.1:8080"
    scene = parse_scene_text("body: {principal_moments: [1.0, 2.0, 3.0]}\nweb: 8080\n")
    assert scene.web == "8080"  # the scene key, the parameter's default


def test_while_nobody_watches_nothing_is_sent_and_the_first_browser_gets_the_latest(page):
    assert page.clients() == 0  # the default: a browser connected
    watching = threading.Event()
    pump = web.FramePump(page, lambda frame, rtf: "", watched=watching.is_set)
    sim = Simulator(load_scene(resolve_scene("free_tumble")), method="rk4")
    try:
        for count in range(1, 11):
            sim.advance(5)
            pump.offer(sim.snapshot())
            deadline = time.monotonic() + 10.0
            while len(pump._history) < count:  # the plots' history is kept meanwhile
                assert time.monotonic() < deadline, "the state never reached the history"
                time.sleep(0.01)
        assert pump.sent == 0
        watching.set()
        deadline = time.monotonic() + 10.0
        while pump.sent == 0:
            assert time.monotonic() < deadline, "the watching browser got nothing"
            time.sleep(0.01)
    finally:
        pump.close()
    assert pump.sent == 1  # the latest, once (nothing new came after)


def test_play_on_a_finished_recording_replays_it_from_the_start():
    """``rigid-rot view --web`` of a recording: Play at the end starts again, as a media player's (issue 40)."""
    from rigid_rot_sim.viewer.web_playback import next_position

    end = 12.0
    assert next_position(end, 0.1, True, 1.0, None, True, end) == (0.0, True)  # ended, Play pressed: from 0
    assert next_position(end, 0.1, True, 1.0, None, False, end) == (end, False)  # ended, nothing pressed: stays
    assert next_position(5.0, 0.1, True, 1.0, None, True, end) == (5.1, False)  # Play while playing: goes on
    assert next_position(5.0, 0.1, False, 1.0, None, False, end) == (5.0, False)  # paused
    assert next_position(5.0, 0.1, True, 1.0, 2.0, False, end) == (2.0, True)  # a seek

"""The body's own web page: a self-hosted 3D view and plots, served by viser, offline.

``http://HOST:PORT/`` shows, drawn from :mod:`rigid_rot_sim.run.body_view` (one drawing for every
viewer):

* the body as its uniform inertia box with its principal axes (red x, green y, blue z of the
  principal frame), turning in the world frame (z up, REP 103); omega (orange, body frame) and
  L (blue, world frame) at run-fixed scales, with a legend; reaction wheels as discs on their
  axes; a fading trail of the tip of the box's longest side;
* plots of omega (body frame), the energy drift and the |L| drift against sim time;
* a status panel (sim time, real-time factor, digest) and the controls of whoever serves the page
  (a live run: pause / resume / step / reset; a recording: play / pause / speed / time slider).

The page is viser's own client (three.js and its GUI, bundled in the viser wheel): the server
sends it over the same port, and the page loads nothing else: no font, CDN, map or image from
anywhere (no Draco mesh, no remote image or font in any text; the share button, which would
reach viser's tunnel service, is hidden). The browser tests check it from the page's network log.

:class:`BodyPage` draws; what feeds it decides the pace. :data:`MAX_RATE` bounds the updates sent
(latest frame wins, the others are dropped): the page never slows whoever simulates.

viser (PyPI, MIT) is an optional extra (``pip install rigid_rot_sim[web]``; ``make setup``
installs it): :func:`available` tells whether it is importable; nothing here imports it before
a page is served.
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import math
import socket
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rigid_rot_sim.run.body_view import (
    BOX_COLOR,
    MOMENTUM_COLOR,
    OMEGA_COLOR,
    TRAIL_COLOR,
    WHEEL_COLOR,
    BodyView,
)

__all__ = [
    "DEFAULT_PORT",
    "MAX_RATE",
    "BodyPage",
    "Frame",
    "FramePump",
    "available",
    "disc_mesh",
    "missing_line",
]

DEFAULT_PORT = 8080
#: Most updates a second sent to the page (frames in between are dropped, never queued).
MAX_RATE = 30.0
#: Plot refreshes a second (each sends the plotted history).
PLOT_RATE = 4.0
#: Samples kept for the plots (at most MAX_RATE a second: about a minute at full rate, then thinned).
PLOT_SAMPLES = 1800
#: Points of the major axis tip's trail.
TRAIL_POINTS = 150
#: What the start-up line says without viser.
missing_line = "web page (viser not installed: pip install rigid_rot_sim[web])"


def available() -> bool:
    """True when viser is installed (the web extra)."""
    return importlib.util.find_spec("viser") is not None


@dataclass(frozen=True)
class Frame:
    """One picture of the body: sim time (s), attitude (x, y, z, w, body -> world), omega (rad/s,
    body frame), L (kg*m^2/s, world frame), the energy and |L| drifts (1) and the run digest."""

    t: float
    orientation: np.ndarray
    omega_body: np.ndarray
    momentum_world: np.ndarray
    energy_drift: float
    momentum_drift: float
    digest: int = 0

    @classmethod
    def of(cls, state: Any) -> Frame:
        """From a :class:`~rigid_rot_sim.run.observables.StateSnapshot`."""
        return cls(
            float(state.t),
            np.asarray(state.orientation, dtype=float),
            np.asarray(state.angular_velocity_body, dtype=float),
            np.asarray(state.angular_momentum_world, dtype=float),
            float(state.energy_drift),
            float(state.angular_momentum_drift),
            int(state.digest),
        )


def _rgb(rgba: tuple[float, float, float, float]) -> tuple[int, int, int]:
    return (round(255 * rgba[0]), round(255 * rgba[1]), round(255 * rgba[2]))


def _wxyz(q: Any) -> tuple[float, float, float, float]:
    """viser's scalar-first order from ours (x, y, z, w)."""
    return (float(q[3]), float(q[0]), float(q[1]), float(q[2]))


def disc_mesh(
    center: Sequence[float], axis: Sequence[float], radius: float, thickness: float, segments: int = 32
) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (m) and triangles of a closed disc (a short cylinder) centred on ``center`` along the unit ``axis``."""
    n = np.asarray(axis, dtype=float)
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(n, helper)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    angles = np.linspace(0.0, 2.0 * math.pi, segments, endpoint=False)
    ring = radius * (np.outer(np.cos(angles), u) + np.outer(np.sin(angles), v))
    c = np.asarray(center, dtype=float)
    top, bottom = c + 0.5 * thickness * n, c - 0.5 * thickness * n
    vertices = np.vstack([ring + top, ring + bottom, top, bottom])
    faces = []
    for i in range(segments):
        j = (i + 1) % segments
        faces += [(i, j, segments + j), (i, segments + j, segments + i)]  # side
        faces += [(2 * segments, j, i), (2 * segments + 1, segments + i, segments + j)]  # caps
    return vertices.astype(np.float32), np.asarray(faces, dtype=np.uint32)


def _check_host(host: str) -> None:
    """OSError naming ``host`` when this machine cannot listen there (viser would wait for ever: it tries
    1000 ports on any bind error, then never reports back)."""
    try:
        family, kind, proto, _, address = socket.getaddrinfo(host, 0, type=socket.SOCK_STREAM)[0]
        with socket.socket(family, kind, proto) as probe:
            probe.bind(address)
    except OSError as exc:
        raise OSError(f"cannot listen on host {host!r}: {exc.strerror or exc}") from None


def _legend(view: BodyView) -> str:
    """What the arrows' lengths mean (the scales are fixed for the run)."""
    return (
        "**Legend**  \n"
        f"orange arrow: ω (body frame), 1 m = {1.0 / view.omega_scale:.4g} rad/s  \n"
        f"blue arrow: L (world frame), 1 m = {1.0 / view.momentum_scale:.4g} kg·m²/s  \n"
        "grey box: the uniform box of the body's principal moments; "
        "red/green/blue axes: principal axes 1/2/3  \n"
        "magenta trail: tip of the box's longest side"
        + ("  \nteal discs: reaction wheels on their axes" if view.wheel_axes else "")
    )


class BodyPage:
    """A viser server showing one body: :meth:`show` a :class:`Frame`, :meth:`status` a line of text.

    ``title`` names the page; the caller adds its controls to :attr:`controls` (a GUI folder).
    Safe to call from any one thread at a time (the pump's or the player's).
    """

    def __init__(self, host: str, port: int, view: BodyView, title: str) -> None:
        import viser
        import viser.uplot

        self.view = view
        _check_host(host)
        with contextlib.redirect_stdout(
            io.StringIO()
        ):  # viser prints a banner whatever `verbose` says: ours names the URL
            server = viser.ViserServer(host=host, port=port, label=title, verbose=False)
        self.server: Any = server  # None once closed
        # no share button (it would reach viser's tunnel service); nothing else on the page leaves the host
        server.gui.configure_theme(show_share_button=False, show_logo=False, control_width="large")
        server.scene.set_up_direction("+z")
        # from the side of +x, -y, a little above: the body fills the view (viser's default is 3 m away)
        server.initial_camera.position = (1.7 * view.size, -1.7 * view.size, 1.1 * view.size)
        server.initial_camera.look_at = (0.0, 0.0, 0.0)
        server.scene.add_grid("/grid", width=4 * view.size, height=4 * view.size, cell_size=0.25 * view.size)
        self._body = server.scene.add_frame("/body", show_axes=False)
        server.scene.add_box(
            "/body/box",
            dimensions=np.maximum(np.asarray(view.box_sides), 1e-3),
            color=_rgb(BOX_COLOR),
            opacity=BOX_COLOR[3],
            position=view.box_center,
            wxyz=_wxyz(view.box_orientation),
        )
        server.scene.add_frame(
            "/body/principal",
            axes_length=0.75 * view.size,
            axes_radius=0.012 * view.size,
            position=view.box_center,
            wxyz=_wxyz(view.box_orientation),
        )
        for i, (axis, center) in enumerate(zip(view.wheel_axes, view.wheel_centers, strict=True)):
            vertices, faces = disc_mesh(center, axis, view.wheel_radius, view.wheel_thickness)
            server.scene.add_mesh_simple(f"/body/wheel_{i}", vertices, faces, color=_rgb(WHEEL_COLOR))
        shaft, head, zero = 0.5 * view.shaft_diameter, view.shaft_diameter, np.zeros((1, 2, 3))
        self._omega = server.scene.add_arrows(
            "/body/omega", zero, _rgb(OMEGA_COLOR), shaft_radius=shaft, head_radius=head, head_length=view.head_size
        )
        self._momentum = server.scene.add_arrows(
            "/momentum", zero, _rgb(MOMENTUM_COLOR), shaft_radius=shaft, head_radius=head, head_length=view.head_size
        )
        self._trail_points: deque[np.ndarray] = deque(maxlen=TRAIL_POINTS)
        self._trail = server.scene.add_line_segments(
            "/trail", np.zeros((1, 2, 3)), _rgb(TRAIL_COLOR), thickness=0.01 * view.size
        )
        self.status_text = server.gui.add_markdown("**waiting for the first state**")
        self.controls = server.gui.add_folder("Controls")
        server.gui.add_markdown(_legend(view))
        with server.gui.add_folder("Plots"):
            self._plots = _Plots(server.gui, viser.uplot)
        self._last_plot = 0.0

    @property
    def port(self) -> int:
        """The port it serves on (the system's choice when 0 was asked, the next free one when taken)."""
        return int(self.server.get_port())

    def clients(self) -> int:
        """Browsers connected now."""
        return len(self.server.get_clients())

    def show(self, frame: Frame, history: Sequence[Frame] = ()) -> None:
        """Turn the body to ``frame`` (and the plots to ``history``, at most ``PLOT_RATE`` times a second)."""
        view = self.view
        tail, tip = view.omega_arrow(frame.omega_body)
        l_tail, l_tip = view.momentum_arrow(frame.momentum_world)
        self._trail_points.append(view.major_axis_tip(frame.orientation))
        with self.server.atomic():
            self._body.wxyz = _wxyz(frame.orientation)
            self._omega.points = np.array([[tail, tip]], dtype=np.float32)
            self._momentum.points = np.array([[l_tail, l_tip]], dtype=np.float32)
            self._draw_trail()
        now = time.monotonic()
        if history and now - self._last_plot >= 1.0 / PLOT_RATE:
            self._last_plot = now
            self._plots.update(history)

    def clear_trail(self) -> None:
        """Start the trail afresh (a jump: a reset, a seek)."""
        self._trail_points.clear()

    def _draw_trail(self) -> None:
        points = np.asarray(self._trail_points)
        if len(points) < 2:
            return
        segments = np.stack([points[:-1], points[1:]], axis=1)
        # fading: the oldest segment nearly white, the newest the trail's colour
        fade = np.linspace(0.1, 1.0, len(segments))[:, None, None]
        color = np.asarray(_rgb(TRAIL_COLOR), dtype=float)
        colors = 255.0 - fade * (255.0 - color)
        self._trail.points = segments.astype(np.float32)
        self._trail.colors = np.repeat(colors, 2, axis=1).astype(np.uint8)

    def status(self, markdown: str) -> None:
        """Replace the status panel's text."""
        self.status_text.content = markdown

    def close(self) -> None:
        """Stop serving (idempotent)."""
        server, self.server = self.server, None
        if server is not None:
            with contextlib.redirect_stdout(io.StringIO()):  # its "Server stopped" (it joins its thread)
                server.stop()


class _Plots:
    """The page's plot panel: omega, energy drift and |L| drift against sim time (uPlot)."""

    def __init__(self, gui: Any, uplot: Any) -> None:
        empty = (np.zeros(1), np.zeros(1))
        x_series = uplot.Series(label="t (s)")
        self.omega = gui.add_uplot(
            (np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1)),
            (
                x_series,
                uplot.Series(label="ωx", stroke="#e4572e", width=2),
                uplot.Series(label="ωy", stroke="#29a329", width=2),
                uplot.Series(label="ωz", stroke="#2e86de", width=2),
            ),
            title="ω, body frame (rad/s)",
            scales={"x": uplot.Scale(time=False, auto=True)},
            aspect=2.0,
        )
        self.energy = gui.add_uplot(
            empty,
            (x_series, uplot.Series(label="energy drift", stroke="#8e44ad", width=2)),
            title="energy drift (E - E0) / |E0|",
            scales={"x": uplot.Scale(time=False, auto=True)},
            aspect=2.5,
        )
        self.momentum = gui.add_uplot(
            empty,
            (x_series, uplot.Series(label="|L| drift", stroke="#2e86de", width=2)),
            title="|L| drift (|L| - |L0|) / |L0|",
            scales={"x": uplot.Scale(time=False, auto=True)},
            aspect=2.5,
        )

    def update(self, history: Sequence[Frame]) -> None:
        t = np.array([f.t for f in history])
        omega = np.array([f.omega_body for f in history]).reshape(-1, 3)
        self.omega.data = (t, omega[:, 0], omega[:, 1], omega[:, 2])
        self.energy.data = (t, np.array([f.energy_drift for f in history]))
        self.momentum.data = (t, np.array([f.momentum_drift for f in history]))


class FramePump:
    """Takes frames from whoever simulates (:meth:`offer`: one assignment, never blocks) and shows the
    latest on a :class:`BodyPage` from a thread of its own, at most ``rate`` times a second.

    Frames offered in between are dropped: a fast run, a slow or stalled browser or none at all
    cost the simulation the same. ``describe(frame, rtf)`` gives the status panel's text.
    ``watched()`` (default: a browser is connected) says whether to send anything: while nobody
    watches, only the plots' history is kept (the updates would be serialised and buffered by viser
    for no one), and a browser that connects gets the latest frame at the next tick.
    """

    def __init__(
        self,
        page: BodyPage,
        describe: Callable[[Frame, float | None], str],
        rate: float = MAX_RATE,
        watched: Callable[[], bool] | None = None,
    ) -> None:
        self.page = page
        self.describe = describe
        self.watched = watched if watched is not None else lambda: page.clients() > 0
        self.period = 1.0 / rate
        self.sent = 0  # frames shown (for the tests and the benchmark)
        self.offered = 0
        self.failure: str | None = None  # the first update that failed (reported once)
        self._latest: Any = None
        self._history: deque[Frame] = deque(maxlen=PLOT_SAMPLES)
        self._rate_anchor: tuple[float, float] | None = None  # (wall s, sim s) of the last rate sample
        self._rtf: float | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="web-page", daemon=True)
        self._thread.start()

    def offer(self, state: Any) -> None:
        """The latest state (anything :meth:`Frame.of` reads); converted on the pump's thread."""
        self._latest = state
        self.offered += 1

    def _run(self) -> None:
        converted: Any = None  # the last state turned into a frame (and added to the history)
        shown: Any = None  # the last state sent to the page
        frame: Frame | None = None
        last_status = 0.0
        while not self._stop.wait(self.period):
            state = self._latest
            try:
                if state is not None and state is not converted:
                    frame, converted = self._convert(state), state
                if frame is None or not self.watched():
                    continue
                if state is not shown:
                    self.page.show(frame, self._history)
                    self.page.status(self.describe(frame, self._rtf))
                    shown, last_status = state, time.monotonic()
                    self.sent += 1
                elif time.monotonic() - last_status >= 0.5:
                    # nothing new (paused, waiting for a turn): the status panel still follows, twice a second
                    self.page.status(self.describe(frame, None))
                    last_status = time.monotonic()
            except Exception as exc:  # the page must not stop the pump quietly: say it once, go on
                if self.failure is None:
                    self.failure = repr(exc)
                    print(f"web page: update failed: {exc!r}", flush=True)

    def _convert(self, state: Any) -> Frame:
        """The frame of ``state``, added to the plots' history; the real-time factor follows about every second."""
        frame = Frame.of(state)
        now = time.monotonic()
        anchor = self._rate_anchor
        if anchor is None or frame.t < anchor[1]:  # the first frame, or a reset
            self._rate_anchor = (now, frame.t)
            self._history.clear()
            self.page.clear_trail()
        elif now - anchor[0] >= 1.0:
            self._rtf = (frame.t - anchor[1]) / (now - anchor[0])
            self._rate_anchor = (now, frame.t)
        self._history.append(frame)
        return frame

    def close(self) -> None:
        """Stop the pump and the page (idempotent)."""
        self._stop.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)
        self.page.close()

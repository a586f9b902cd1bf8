"""The node's web page (``--web`` / the ``web`` parameter): an observer of the run, and a client of its services.

The page (:mod:`rigid_rot_sim.viewer.web`) stays off the simulation's path: as an observer of the
run driver it only keeps a reference to the latest state it is told of (``outputs_due``: the
snapshot the outputs publish, no copy, no serialisation); the page's own thread turns that into
at most ``MAX_RATE`` updates a second and drops the rest. Its buttons call the node's own
services (``~/pause``, ``~/step``, ``~/reset``) through ROS clients, as any other client would:
what they do is recorded and re-simulated like any other request, and the page holds no handle
on the run. A browser that connects, disconnects or stalls changes no state bit.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from rclpy.node import Node
from std_srvs.srv import SetBool, Trigger

from rigid_rot_msgs.srv import Step  # generated, untyped (as ros/controller.py)
from rigid_rot_sim.run.body_view import BodyView
from rigid_rot_sim.run.digest import format_digest
from rigid_rot_sim.run.observer import SimulationObserver
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.viewer.foxglove import parse_address
from rigid_rot_sim.viewer.web import BodyPage, Frame, FramePump, available, missing_line

__all__ = ["WebLive", "start"]

#: Steps one press of "step" asks for (the page's number field starts there).
STEP_BUTTON_STEPS = 10


class WebLive(SimulationObserver):
    """Hands each state the outputs publish to the page's pump (an observer of the run driver)."""

    def __init__(self, pump: FramePump) -> None:
        self.pump = pump

    def outputs_due(self, step: int, snapshot: Any, names: Sequence[str]) -> None:
        self.pump.offer(snapshot)

    def close(self) -> None:
        self.pump.close()


class _Buttons:
    """Pause, resume, step and reset: requests to the node's own services, answered in the status panel."""

    def __init__(self, node: Node, page: BodyPage) -> None:
        self.page = page
        self.reply = "no command sent yet"
        self._pause = node.create_client(SetBool, "~/pause")
        self._step = node.create_client(Step, "~/step")
        self._reset = node.create_client(Trigger, "~/reset")
        gui = page.server.gui
        with page.controls:
            gui.add_button("Pause").on_click(lambda _: self._call("pause", self._pause, SetBool.Request(data=True)))
            gui.add_button("Resume").on_click(lambda _: self._call("resume", self._pause, SetBool.Request(data=False)))
            steps = gui.add_number("steps", initial_value=STEP_BUTTON_STEPS, min=1, step=1)
            gui.add_button("Step").on_click(
                lambda _: self._call("step", self._step, Step.Request(steps=max(1, int(steps.value))))
            )
            gui.add_button("Reset").on_click(lambda _: self._call("reset", self._reset, Trigger.Request()))

    def _call(self, what: str, client: Any, request: Any) -> None:
        """Send without waiting (the reply comes through the node's executor)."""
        self.reply = f"{what}: sent"
        future = client.call_async(request)
        future.add_done_callback(lambda f: self._answered(what, f))

    def _answered(self, what: str, future: Any) -> None:
        response = future.result()
        if response is None:
            self.reply = f"{what}: no reply"
        else:
            self.reply = f"{what}: {'ok' if response.success else 'refused'} ({response.message or '-'})"


def start(address: str, node: Node, sim: Simulator, view: BodyView, title: str) -> tuple[WebLive | None, str]:
    """The page on ``[HOST:]PORT`` and the start-up line's words; (None, why) without viser.

    ValueError for a malformed address; OSError when the host cannot be bound.
    """
    host, port = parse_address(address, what="web page")
    if not available():
        return None, missing_line
    page = BodyPage(host, port, view, title)
    buttons = _Buttons(node, page)

    def describe(frame: Frame, rtf: float | None) -> str:
        return (
            f"**{title}**  \n"
            f"sim time: {frame.t:.3f} s{' (paused)' if sim.paused else ''}  \n"
            f"real-time factor: {'-' if rtf is None else f'{rtf:.2f}'}  \n"
            f"digest: {format_digest(frame.digest)}  \n"
            f"last command: {buttons.reply}"
        )

    return WebLive(FramePump(page, describe)), f"web page http://{host}:{page.port}/"

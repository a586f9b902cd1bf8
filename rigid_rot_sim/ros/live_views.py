"""The node's optional live viewers: the Foxglove live server and the body's web page.

Each is built only when its read-only parameter (``foxglove``, ``web``) names an address, and only
when its extra is installed (foxglove-sdk, viser); otherwise the start-up line says what was left out
and why. Both stay off the simulation's path: the Foxglove server listens to the outputs (the bytes
published), the web page observes the run driver (the latest state, at most 30 updates a second).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from rclpy.node import Node

from rigid_rot_sim.ros.outputs import Outputs
from rigid_rot_sim.run.pacing import RunDriver
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import Scene

if TYPE_CHECKING:  # imported when asked for only: the extras are optional
    from rigid_rot_sim.ros.foxglove_live import FoxgloveLive
    from rigid_rot_sim.ros.web_live import WebLive

__all__ = ["LiveView", "start", "start_foxglove", "start_web"]


@dataclass
class LiveView:
    """A live viewer as a part of the node's run (:class:`~rigid_rot_sim.ros.parts.Part`): built, or left
    out and why (the start-up line's words); closed with the run."""

    live: FoxgloveLive | WebLive | None
    words: str

    def describe(self) -> tuple[list[str], list[str]]:
        if not self.words:
            return [], []
        return ([self.words], []) if self.live is not None else ([], [self.words])

    def close(self) -> None:
        if self.live is not None:
            self.live.close()


def start(
    node: Node, foxglove: str, web: str, sim: Simulator, outputs: Outputs, driver: RunDriver, scene: Scene
) -> list[LiveView]:
    """The live viewers the ``foxglove`` and ``web`` addresses ask for; ValueError when one cannot serve."""
    views = [LiveView(*start_foxglove(node, foxglove, sim, outputs, scene))]
    try:
        views.append(LiveView(*start_web(node, web, sim, outputs, driver, scene)))
    except BaseException:
        views[0].close()
        raise
    return views


def start_foxglove(
    node: Node, address: str, sim: Simulator, outputs: Outputs, scene: Scene
) -> tuple[FoxgloveLive | None, str]:
    """The Foxglove live server, a listener of the outputs (None without an address or foxglove-sdk),
    and the words for the start-up line; ValueError when it cannot serve on ``address``."""
    if not address:
        return None, ""
    from rigid_rot_sim.ros import foxglove_live

    name = node.get_namespace().rstrip("/") + "/" + node.get_name()
    try:
        live, words = foxglove_live.start(address, sim, outputs.body_view, scene.frames, name)
    except (OSError, RuntimeError) as exc:  # the port is taken, the host is not ours
        raise ValueError(f"foxglove: cannot serve on {address}: {exc}") from None
    if live is not None:
        outputs.listeners.append(live)  # every message published, as the bytes published
    return live, words


def start_web(
    node: Node, address: str, sim: Simulator, outputs: Outputs, driver: RunDriver, scene: Scene
) -> tuple[WebLive | None, str]:
    """The web page, an observer of the run driver (None without an address or viser), and the words
    for the start-up line; ValueError when it cannot serve on ``address``."""
    if not address:
        return None, ""
    from rigid_rot_sim.ros import web_live

    title = f"rigid_rot_sim: {scene.name}"
    try:
        live, words = web_live.start(address, node, sim, outputs.body_view, title)
    except (OSError, RuntimeError) as exc:  # the host is not ours
        raise ValueError(f"web: cannot serve on {address}: {exc}") from None
    if live is not None:
        driver.observers.append(live)  # the states the outputs publish, as snapshots (no copy)
    return live, words

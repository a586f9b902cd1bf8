"""What a run reports to the parts that act on it: one small interface, no ROS.

The simulator (and the run driver that paces it) tell their observers what happened, in
the order it happened: a command accepted or rejected, a torque applied for a duration, a
state set, a reset, an integrator change, a failure, and the outputs due at a step. The
ROS outputs and the recorder are two observers of the same stream, so a command's route
from its subscription to the integrator and to the file is one path, read top to bottom,
with no method or publisher wrapped at run time.

Every call carries ``step``: the step index at which it happened (the simulator's
``clock.k`` *before* the change took effect), so that a recording of the calls
re-simulates the run exactly. Observers must not raise: a failing observer (a full disk)
reports its own error and stays quiet afterwards; the run goes on.

:class:`SimulationObserver` is a base class with a no-op for every report, so an observer
overrides only what it uses.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the dataclasses only; nothing here depends on the simulator at run time
    from rigid_rot_sim.run.commands import TorqueCommand
    from rigid_rot_sim.run.observables import StateSnapshot


class SimulationObserver:
    """Receives a run's reports; every method is a no-op until overridden."""

    def command_accepted(self, step: int, command: TorqueCommand) -> None:
        """A topic (or resim) torque command was scheduled; it takes effect at ``command.step``."""

    def command_rejected(self, step: int, source: str, reason: str, frame_id: str, torque: Any) -> None:
        """A command on ``source`` was refused for ``reason`` (``torque`` as received, maybe not finite)."""

    def wheel_command_accepted(
        self, step: int, source: str, torques: Sequence[float], effective_time: float, clamped: Sequence[int]
    ) -> None:
        """Wheel motor torques (N*m, clamped, scene order) were scheduled on ``source`` for ``effective_time``
        (s); ``clamped`` lists the wheels whose command exceeded max_torque."""

    def rod_command_accepted(
        self, step: int, source: str, dipoles: Sequence[float], effective_time: float, clamped: Sequence[int]
    ) -> None:
        """Torque-rod dipoles (A*m^2, clamped, scene order) were scheduled on ``source`` for ``effective_time``
        (s); ``clamped`` lists the rods whose command exceeded max_dipole."""

    def torque_applied(self, step: int, command: TorqueCommand) -> None:
        """A torque for ``command.duration`` s was scheduled (the ``apply_torque`` request)."""

    def state_set(self, step: int, orientation: Sequence[float], angular_velocity: Sequence[float]) -> None:
        """The state was replaced: orientation (x, y, z, w) body -> world, ω (rad/s) in the body frame."""

    def reset(self, step: int) -> None:
        """The run went back to the scene's initial state."""

    def integrator_changed(self, step: int, method: str, dt: float, options: dict[str, Any]) -> None:
        """The method, the step dt (s) or the method's options changed from this step on."""

    def failed(self, step: int, reason: str) -> None:
        """The run stopped at ``step`` (a non-finite or out-of-limits state); the last good state is kept.

        ``reason`` is :attr:`Simulator.failure <rigid_rot_sim.run.simulator.Simulator.failure>`.
        """

    def lockstep_timeout(self, step: int, reason: str, action: str) -> None:
        """A lockstep turn at ``step`` timed out for ``reason``; ``action`` is ``pause`` or ``hold``.

        Told by the lockstep turns (:mod:`~rigid_rot_sim.run.lockstep`); states do not depend on it.
        """

    def outputs_due(self, step: int, snapshot: StateSnapshot, names: Sequence[str]) -> None:
        """The outputs ``names`` (scene output names) are due at ``step``, with the state there.

        Told by the run driver (:mod:`~rigid_rot_sim.run.pacing`), never by the simulator.
        """

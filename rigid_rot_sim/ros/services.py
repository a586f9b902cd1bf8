"""The node's own services: ``~/compute_inertia`` and the run's actions.

Every service answers ``success`` and a ``message`` (the reason when refused); nothing
raises out of a callback. The actions (:meth:`RunServices.reset`, :meth:`~RunServices.pause`,
:meth:`~RunServices.step`, :meth:`~RunServices.set_state`) are public: the standard
``simulation_interfaces`` services (:mod:`.simulation_services`) call the same code.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from std_srvs.srv import SetBool, Trigger

from rigid_rot_msgs.srv import (  # generated, untyped
    ApplyTorque,
    ComputeInertia,
    SetState,
    Step,
    StepWithTorque,
)
from rigid_rot_sim import conversions
from rigid_rot_sim.core import limits
from rigid_rot_sim.core.inertia import mass_properties
from rigid_rot_sim.ros.inputs import REJECT_WARN_PERIOD, Rejections
from rigid_rot_sim.run.pacing import Progress, RunDriver
from rigid_rot_sim.run.simulator import CommandRejected
from rigid_rot_sim.run.step_requests import torque_for_steps
from rigid_rot_sim.scene.scene import Scene

#: Most wall time (s) one ~/step request spends stepping; the reply says if it stopped short.
STEP_REQUEST_WALL = 0.25


class InertiaService:
    """``~/compute_inertia``: mass properties of point masses (served with or without a scene).

    In a callback group of its own: rclpy turns a request into Python objects in the thread
    that takes it (2.4 s for 1e6 masses, refused only afterwards); the node's run loop steps,
    publishes and takes the commands on a thread of its own (:mod:`.run_loop`), so a huge request is
    taken beside them, without the run lock. Thread-safe: it touches nothing but its request and response.
    What such a request still costs in memory (rclpy offers no way to refuse it before it is taken):
    docs/limits.md, measured by ``benchmarks/inertia_request_memory.py``.
    """

    def __init__(self, node: Node) -> None:
        self.logger = node.get_logger()
        self.callback_group = MutuallyExclusiveCallbackGroup()
        self.service = node.create_service(
            ComputeInertia, "~/compute_inertia", self.compute_inertia_callback, callback_group=self.callback_group
        )

    def compute_inertia_callback(self, request, response):
        count = max(len(request.masses), len(request.positions))
        if count > limits.MAX_POINT_MASSES:  # refused before converting anything
            return self._refuse(
                response, f"invalid request: {count} masses, more than the limit of {limits.MAX_POINT_MASSES}"
            )
        if len(request.frame_id) > limits.MAX_NAME_LENGTH:
            return self._refuse(
                response,
                f"invalid request: frame_id of {len(request.frame_id)} characters exceeds the limit of "
                f"{limits.MAX_NAME_LENGTH}",
            )
        try:
            masses, positions, origin = conversions.compute_inertia_request_to_arrays(request)
            props = mass_properties(masses, positions, origin)
            conversions.fill_compute_inertia_response(response, props)
        except ValueError as exc:
            return self._refuse(response, f"invalid request: {exc}")
        except Exception as exc:  # a callback must never raise: the node keeps serving
            self.logger.error(f"compute_inertia failed: {exc!r}")
            return self._refuse(response, f"internal error: {exc!r}")
        response.success = True
        response.message = f"{len(masses)} masses, {props.total_mass:.6g} kg, {props.symmetry}"
        return response

    def _refuse(self, response, message: str):
        self.logger.warning(message, throttle_duration_sec=REJECT_WARN_PERIOD)
        response.success = False
        response.message = message
        return response


class _Logged(ValueError):
    """A refusal already logged (a rejected command: ~/rejected and its throttled warning): not logged again."""


class RunServices:
    """``~/set_state``, ``~/reset``, ``~/pause``, ``~/step``, ``~/apply_torque``, ``~/step_with_torque`` on ``run``.

    ``report`` logs what a slice of stepping came to (a failure, the duration reached).
    """

    def __init__(
        self, node: Node, run: RunDriver, scene: Scene, rejections: Rejections, report: Callable[[Progress], None]
    ) -> None:
        self.logger = node.get_logger()
        self.run = run
        self.sim = run.sim
        self.scene = scene
        self.frames = scene.frames
        self.rejections = rejections
        self.report = report
        self.apply_torque_name = node.resolve_service_name("~/apply_torque")
        self.step_with_torque_name = node.resolve_service_name("~/step_with_torque")
        self.services = [
            node.create_service(SetState, "~/set_state", self.set_state_callback),
            node.create_service(Trigger, "~/reset", self.reset_callback),
            node.create_service(SetBool, "~/pause", self.pause_callback),
            node.create_service(Step, "~/step", self.step_callback),
            node.create_service(ApplyTorque, "~/apply_torque", self.apply_torque_callback),
            node.create_service(StepWithTorque, "~/step_with_torque", self.step_with_torque_callback),
        ]

    # ------------------------------------------------------------------ callbacks

    def set_state_callback(self, request, response):
        return self.serve(
            response,
            "~/set_state",
            lambda: self.set_state(
                conversions.quaternion_to_array(request.orientation),
                conversions.vector3_to_array(request.angular_velocity),
            ),
        )

    def reset_callback(self, request, response):
        return self.serve(response, "~/reset", self.reset)

    def pause_callback(self, request, response):
        return self.serve(response, "~/pause", lambda: self.pause(bool(request.data)))

    def step_callback(self, request, response):
        def step() -> str:
            try:
                return self.step(int(request.steps))
            finally:
                self.fill_state(response.state)

        return self.serve(response, "~/step", step)

    def step_with_torque_callback(self, request, response):
        def step_with_torque() -> str:
            try:
                torque = conversions.vector3_to_array(request.torque)
                return self.step_with_torque(torque, request.frame_id, int(request.steps))
            finally:
                self.fill_state(response.state)

        return self.serve(response, "~/step_with_torque", step_with_torque)

    def fill_state(self, message: Any) -> None:
        """``message`` (RigidBodyState) from the current state."""
        conversions.fill_rigid_body_state(message, self.sim.snapshot(), self.frames.world, self.frames.body)

    def apply_torque_callback(self, request, response):
        def apply() -> str:
            torque = conversions.vector3_to_array(request.torque)
            duration = conversions.time_to_seconds(request.duration)
            try:
                command = self.sim.apply_torque(torque, request.frame_id, duration)
            except CommandRejected as exc:
                self.rejections.reject(self.apply_torque_name, exc.reason, request.frame_id, torque)
                raise _Logged(exc.reason) from None
            return (
                f"torque {list(command.torque)} N*m ({command.frame} frame) from t = {command.effective_time:.9g} s "
                f"for {duration:g} s"
            )

        return self.serve(response, "~/apply_torque", apply)

    def serve(self, response, name: str, action: Callable[[], str]) -> Any:
        """Run a service action: success with its message, or success=false with the reason."""
        try:
            response.message = action()
            response.success = True
        except ValueError as exc:
            response.success = False
            response.message = str(exc)
            if not isinstance(exc, _Logged):
                self.logger.warning(f"{name} refused: {exc}")
        except Exception as exc:  # a callback must never raise: the node keeps serving
            response.success = False
            response.message = f"internal error: {exc!r}"
            self.logger.error(f"{name} failed: {exc!r}")
        return response

    # ------------------------------------------------------------------ actions (ValueError: refused)

    def set_state(self, orientation: Any, angular_velocity: Any) -> str:
        """Replace the state at the current time and publish every output."""
        self.sim.set_state(orientation, angular_velocity)
        self.run.publish_due(force=True)
        return f"state set at t = {self.sim.clock.t:.9g} s; {self._run_state()}"

    def set_initial_state(self) -> str:
        """The scene's initial attitude and ω at the current time (a reset of the state only)."""
        initial = self.scene.initial
        return self.set_state(initial.orientation, initial.angular_velocity)

    def reset(self) -> str:
        self.sim.reset()
        self.run.restart()
        self.run.publish_due(force=True)
        return f"reset to the scene's initial state at t = 0; {self._run_state()}"

    def _run_state(self) -> str:
        """What the run does after a reset or set_state (a failure's pause is lifted, a requested one stays)."""
        if not self.sim.paused:
            return "running"
        return "still paused as requested before (~/pause data=false resumes)"

    def pause(self, paused: bool) -> str:
        sim = self.sim
        if not paused and sim.failure is not None:
            raise ValueError(f"cannot resume after a failure ({sim.failure}); reset or set_state first")
        sim.pause(paused)
        if not paused:
            self.run.pacer.anchor(sim.clock.t)
        return f"{'paused' if paused else 'running'} at t = {sim.clock.t:.9g} s"

    def check_step(self, steps: int) -> None:
        """ValueError unless a paused run can be stepped ``steps`` times in one request."""
        if not self.sim.paused:
            raise ValueError("not paused: call ~/pause with data=true first")
        if steps < 1:
            raise ValueError("steps must be >= 1")
        if steps > limits.MAX_STEPS_PER_REQUEST:
            raise ValueError(
                f"steps = {steps} exceeds the limit of {limits.MAX_STEPS_PER_REQUEST} per request "
                "(call ~/step again, or resume with ~/pause data=false)"
            )

    def step_with_torque(self, torque: Any, frame_id: str, steps: int) -> str:
        """Apply ``torque`` over exactly the next ``steps`` steps of a paused run, then step them.

        Atomic: a refused request (not paused, steps out of range, a bad torque or frame) applies
        nothing and steps nothing; no other callback runs in between (one executor callback).
        A request that runs out of its wall-time budget (as ``~/step``) keeps its torque scheduled
        over the remaining steps: ``~/step`` finishes them.
        """
        self.check_step(steps)
        try:
            command = torque_for_steps(self.sim, torque, frame_id, steps)
        except CommandRejected as exc:
            self.rejections.reject(self.step_with_torque_name, exc.reason, frame_id, torque)
            raise ValueError(exc.reason) from None
        done = self.step(steps)
        return f"torque {list(command.torque)} N*m ({command.frame} frame) from step {command.step}; {done}"

    def step(self, steps: int) -> str:
        """Advance a paused run by ``steps`` steps (~/step and ~/step_simulation).

        At most ``limits.MAX_STEPS_PER_REQUEST`` steps, run here in the service callback for
        at most ``STEP_REQUEST_WALL`` s of wall time, so the executor is never held for long.
        """
        sim = self.sim
        self.check_step(steps)
        start = sim.clock.k
        self.report(self.run.run(start + steps, self.run.clock() + STEP_REQUEST_WALL))
        done = sim.clock.k - start
        if sim.failure is not None:
            raise ValueError(f"stopped after {done} steps: {sim.failure}")
        if done < steps:
            raise ValueError(
                f"only {done} of {steps} steps done within the {STEP_REQUEST_WALL:g} s budget of a request "
                f"(t = {sim.clock.t:.9g} s): call ~/step again for the rest"
            )
        return f"{done} steps done, t = {sim.clock.t:.9g} s"

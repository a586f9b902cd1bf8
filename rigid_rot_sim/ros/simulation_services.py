"""The standard simulator services of ``simulation_interfaces`` on top of the node's own.

``simulation_interfaces`` is the ROS 2 simulator standard released into Jazzy (Gazebo,
Isaac Sim and O3DE serve it). The node serves the part that fits a single rigid body, under
the ``simulation_interfaces_namespace`` parameter (scene key of the same name): ``~`` (the
default) puts them under the node's name, as Gazebo does (``/gzserver/step_simulation``);
``/`` at root names (``/step_simulation``), where Isaac Sim and O3DE serve them and generic
clients of the standard look for them; any other namespace (``sim``, ``/sat1/sim``) as ROS
resolves it. Names below for ``~``:

============================  ========================  ============================================
``~/get_simulator_features``  GetSimulatorFeatures      what is served (:data:`FEATURE_INTERFACES`)
``~/get_simulation_state``    GetSimulationState        PLAYING, PAUSED or STOPPED
``~/set_simulation_state``    SetSimulationState        play, pause, stop (= pause + reset)
``~/step_simulation``         StepSimulation            n steps while paused (as ``~/step``)
``~/reset_simulation``        ResetSimulation           time and state, or state only
``~/simulate_steps``          SimulateSteps (action)    as many steps, feedback at most 50 Hz, cancel
============================  ========================  ============================================

SetSimulationState answers every state SimulationState.msg defines: STOPPED, PLAYING, PAUSED as
above; QUITTING with ``RESULT_FEATURE_UNSUPPORTED`` (stop the node with SIGINT or SIGTERM);
NO_WORLD and LOADING_WORLD with ``INCORRECT_TRANSITION``: the .msg describes them as states in
which "the simulation is inactive and cannot be started, stopped, or paused", reached by
unloading or loading a world (LoadWorld, UnloadWorld: not served, the world is the scene loaded at
start-up), never targets of SetSimulationState. GetSimulationState never reports them.

Every call goes through the action behind the node's own service
(:class:`~rigid_rot_sim.ros.services.RunServices`: ``step``, ``reset``, ``pause``,
``set_initial_state``), so their checks, limits and the recording of what changed apply to both.
The outcome is a ``simulation_interfaces/msg/Result``:
``RESULT_FEATURE_UNSUPPORTED`` for what this simulator cannot do (a reset of time alone,
QUITTING), ``RESULT_OPERATION_FAILED`` with the node's reason otherwise, stepping while
playing included: StepSimulation.srv and SimulateSteps.action say so ("Calling with
simulation not paused will return RESULT_OPERATION_FAILED"), and O3DE does the same,
although Result.msg gives this very case as its example of ``RESULT_INCORRECT_STATE``.

The package is optional: it is imported here only, and :data:`AVAILABLE` is False when
it is not installed (an apt install without ``ros-jazzy-simulation-interfaces``); the node
then runs without these services and says so in its start-up line. ``make setup`` builds
it into the venv from ``rigid_rot_msgs/vendor/simulation_interfaces``. Constant names have
differed between versions of the package (``RESULT_OK`` / ``OK``); they are looked up under
either name, their values being the same (constants are not part of the type hash).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rigid_rot_sim.core import limits

try:
    from simulation_interfaces.msg import Result, SimulationState, SimulatorFeatures
    from simulation_interfaces.srv import (
        GetSimulationState,
        GetSimulatorFeatures,
        ResetSimulation,
        SetSimulationState,
        StepSimulation,
    )
except ImportError:  # pragma: no cover - depends on the installation
    AVAILABLE = False
else:
    AVAILABLE = True
try:
    from simulation_interfaces.action import SimulateSteps
except ImportError:  # pragma: no cover - an installation without the action's type support
    SimulateSteps = None


def _constant(cls: type, name: str, prefix: str) -> int:
    """``cls.<prefix><name>`` or ``cls.<name>``, whichever this version of the package defines."""
    for candidate in (prefix + name, name):
        if hasattr(cls, candidate):
            return int(getattr(cls, candidate))
    raise AttributeError(f"{cls.__name__} defines neither {prefix + name} nor {name}")


if AVAILABLE:
    OK, FEATURE_UNSUPPORTED, INCORRECT_STATE, OPERATION_FAILED = (
        _constant(Result, name, "RESULT_")
        for name in ("OK", "FEATURE_UNSUPPORTED", "INCORRECT_STATE", "OPERATION_FAILED")
    )
    STOPPED, PLAYING, PAUSED, QUITTING = (
        _constant(SimulationState, name, "STATE_") for name in ("STOPPED", "PLAYING", "PAUSED", "QUITTING")
    )
    #: The world-loading states of 1.5 (absent from older versions of the package).
    WORLD_STATES = {
        _constant(SimulationState, name, "STATE_"): name
        for name in ("NO_WORLD", "LOADING_WORLD")
        if hasattr(SimulationState, "STATE_" + name) or hasattr(SimulationState, name)
    }

#: ResetSimulation scope bits (the values of the request's SCOPE_* constants).
SCOPE_DEFAULT, SCOPE_TIME, SCOPE_STATE, SCOPE_SPAWNED, SCOPE_ALL = 0, 1, 2, 4, 255

SERVICE_NAMES = (
    "~/get_simulator_features",
    "~/get_simulation_state",
    "~/set_simulation_state",
    "~/step_simulation",
    "~/reset_simulation",
)
#: The node's private names: the default ``simulation_interfaces_namespace``.
PRIVATE = "~"
#: SimulatorFeatures code name -> the service or action (name under the namespace) it says is served.
FEATURE_INTERFACES = {
    "SIMULATION_RESET": "reset_simulation",
    "SIMULATION_RESET_TIME": "reset_simulation",
    "SIMULATION_RESET_STATE": "reset_simulation",
    "SIMULATION_STATE_GETTING": "get_simulation_state",
    "SIMULATION_STATE_SETTING": "set_simulation_state",
    "SIMULATION_STATE_PAUSE": "set_simulation_state",
    "STEP_SIMULATION_SINGLE": "step_simulation",
    "STEP_SIMULATION_MULTIPLE": "step_simulation",
    "STEP_SIMULATION_ACTION": "simulate_steps",
}


def served_name(namespace: str, name: str) -> str:
    """``name`` (e.g. ``step_simulation``) under ``namespace``: ``~`` -> ``~/name``, ``/`` -> ``/name``,
    ``ns`` -> ``ns/name`` (relative to the node's namespace), ``/ns`` -> ``/ns/name``.

    ValueError for an empty namespace or one with whitespace (ROS's own check of the full name follows).
    """
    text = namespace.strip()
    if not text or text != namespace or any(c.isspace() for c in text):
        raise ValueError(
            f"simulation_interfaces_namespace must be '~', '/' or a namespace without whitespace, got {namespace!r}"
        )
    return f"{text.rstrip('/')}/{name}" if text != "/" else f"/{name}"


class _Refused(Exception):
    """A request refused with a Result code and a reason."""

    def __init__(self, code: int, reason: str) -> None:
        super().__init__(reason)
        self.code = code


class SimulationServices:
    """The five services and the action, created on ``node`` under ``namespace`` (``~``: the node's
    private names), acting through ``actions`` (the node's own services)."""

    def __init__(self, node: Any, actions: Any, namespace: str = PRIVATE) -> None:
        if not AVAILABLE:
            raise RuntimeError("simulation_interfaces is not installed")
        self.node = node
        self.actions = actions
        self.run = actions.run
        self.namespace = namespace
        self._stopped = False  # set by SetSimulationState(STOPPED) until played or stepped
        self.names = [served_name(namespace, name.removeprefix("~/")) for name in SERVICE_NAMES]
        callbacks = (
            (GetSimulatorFeatures, self.get_features_callback),
            (GetSimulationState, self.get_state_callback),
            (SetSimulationState, self.set_state_callback),
            (StepSimulation, self.step_callback),
            (ResetSimulation, self.reset_callback),
        )
        self.services = [
            node.create_service(kind, name, callback)
            for name, (kind, callback) in zip(self.names, callbacks, strict=True)
        ]
        self.simulate_steps = None
        self._closed = False
        if SimulateSteps is not None:
            from rigid_rot_sim.ros.simulate_steps import SimulateStepsAction

            self.simulate_steps = SimulateStepsAction(
                node, self, SimulateSteps, OK, OPERATION_FAILED, served_name(namespace, "simulate_steps")
            )

    def describe(self) -> tuple[list[str], list[str]]:
        """For the start-up line (:class:`~rigid_rot_sim.ros.parts.Part`): where the services are."""
        first = self.services[3].srv_name  # the fully resolved name of step_simulation
        return [f"simulation_interfaces services ({first}, ...{', SimulateSteps' if self.simulate_steps else ''})"], []

    def close(self) -> None:
        """Destroy the action server (idempotent): rclpy's destroy_node leaves action servers alone, and one
        left holds the node, which then stays on the graph after destroy_node."""
        if self.simulate_steps is not None and not self._closed:
            self.simulate_steps.destroy()
        self._closed = True

    # ------------------------------------------------------------------ queries

    def get_features_callback(self, request, response):
        try:
            self._fill_features(response.features)
        except Exception as exc:  # a callback must never raise (e.g. a package version without a constant)
            self.node.get_logger().error(f"~/get_simulator_features failed: {exc!r}")
        return response

    def _fill_features(self, features: Any) -> None:
        features.features = [getattr(SimulatorFeatures, name) for name in self.feature_names()]
        features.custom_info = (
            "rigid_rot_sim: one rigid body (Euler's equations) driven by torque topics. ResetSimulation scopes: "
            "DEFAULT/ALL or TIME|STATE = time and state, STATE = state only at the current time (TIME alone: "
            "unsupported); nothing is spawned. "
            f"Also served: {self.node.get_name()}'s ~/step (returns the state), ~/set_state, ~/apply_torque, "
            "~/step_with_torque (a torque over the next N steps, then the state, in one call). "
            f"StepSimulation and ~/step: at most {limits.MAX_STEPS_PER_REQUEST} steps per request (more are "
            "refused with OPERATION_FAILED; SimulateSteps takes any number). "
            "SetSimulationState: STOPPED = reset + pause; from STOPPED, PAUSED keeps the initial state paused. "
            "SimulateSteps: feedback at most 50 times per second of wall time and always after the last step; "
            "a cancel is honoured within 20 ms."
        )

    def feature_names(self) -> list[str]:
        """The SimulatorFeatures codes this node serves (keys of :data:`FEATURE_INTERFACES`), by name.

        SIMULATION_RESET_TIME is not among them: time cannot be reset without the state.
        """
        names = [name for name in FEATURE_INTERFACES if name != "SIMULATION_RESET_TIME"]
        return [name for name in names if name != "STEP_SIMULATION_ACTION" or self.simulate_steps is not None]

    def run_state(self) -> int:
        """SimulationState code of the run now."""
        run = self.run
        if run.finished or (self._stopped and run.sim.paused and run.sim.clock.k == 0):
            return STOPPED
        return PAUSED if run.sim.paused else PLAYING

    def get_state_callback(self, request, response):
        return self._serve(
            "~/get_simulation_state", response, lambda: setattr(response.state, "state", self.run_state())
        )

    # ------------------------------------------------------------------ changes

    def set_state_callback(self, request, response):
        return self._serve("~/set_simulation_state", response, lambda: self._set_run_state(int(request.state.state)))

    def _set_run_state(self, target: int) -> None:
        actions = self.actions
        current = self.run_state()
        already = SetSimulationState.Response.ALREADY_IN_TARGET_STATE
        names = {STOPPED: "STOPPED", PLAYING: "PLAYING", PAUSED: "PAUSED"}
        if target == QUITTING:
            raise _Refused(FEATURE_UNSUPPORTED, "QUITTING is not supported: stop the node with SIGINT or SIGTERM")
        if target in WORLD_STATES:
            raise _Refused(
                SetSimulationState.Response.INCORRECT_TRANSITION,
                f"{WORLD_STATES[target]} is not a target of SetSimulationState: a world is unloaded or loaded "
                "through UnloadWorld / LoadWorld, which this simulator does not serve (its world is the scene, "
                "loaded at start-up)",
            )
        if target not in names:
            raise _Refused(
                OPERATION_FAILED,
                f"unknown simulation state {target} (STOPPED 0, PLAYING 1, PAUSED 2, QUITTING 3, NO_WORLD 4, "
                "LOADING_WORLD 5)",
            )
        if target == current:
            raise _Refused(already, f"already {names[target]}")
        if self.run.finished:
            raise _Refused(
                SetSimulationState.Response.STATE_TRANSITION_ERROR, "the run reached its duration and is stopping"
            )
        if target == STOPPED:
            actions.reset()  # ~/reset
            actions.pause(True)  # ~/pause
            self._stopped = True
            return
        try:
            actions.pause(target == PAUSED)  # ~/pause
        except ValueError as exc:  # e.g. resuming after a failure
            raise _Refused(SetSimulationState.Response.STATE_TRANSITION_ERROR, str(exc)) from None
        self._stopped = False

    def step_callback(self, request, response):
        return self._serve("~/step_simulation", response, lambda: self._step(int(request.steps)))

    def _step(self, steps: int) -> None:
        run = self.run
        if run.finished or not run.sim.paused:
            state = "stopping (duration reached)" if run.finished else "playing"
            raise _Refused(
                OPERATION_FAILED,
                f"stepping needs a paused simulation, it is {state}: pause it first (SetSimulationState PAUSED)",
            )
        self.stepping_started()
        self.actions.step(steps)  # ~/step (ValueError: operation failed)

    def stepping_started(self) -> None:
        """A step request (service or action) was accepted: the run is no longer STOPPED."""
        self._stopped = False

    def reset_callback(self, request, response):
        # the scope field came with the 1.x releases; without it, a reset is a full one
        return self._serve("~/reset_simulation", response, lambda: self._reset(int(getattr(request, "scope", 0))))

    def _reset(self, scope: int) -> None:
        time_bit, state_bit, spawned_bit = SCOPE_TIME, SCOPE_STATE, SCOPE_SPAWNED
        if scope in (SCOPE_DEFAULT, SCOPE_ALL):
            scope = time_bit | state_bit | spawned_bit
        if scope & ~(time_bit | state_bit | spawned_bit):
            raise _Refused(FEATURE_UNSUPPORTED, f"unknown scope bits in {scope} (TIME 1, STATE 2, SPAWNED 4)")
        if scope & time_bit and not scope & state_bit:
            raise _Refused(
                FEATURE_UNSUPPORTED,
                "time cannot be reset without the state (the scene's initial state belongs to t = 0): "
                "use scope TIME|STATE, DEFAULT or ALL",
            )
        if scope & time_bit:
            self.actions.reset()  # ~/reset
        elif scope & state_bit:
            self.actions.set_initial_state()  # ~/set_state with the scene's initial state
        # SPAWNED: nothing is ever spawned here, so there is nothing to remove

    # ------------------------------------------------------------------ plumbing

    def _serve(self, name: str, response: Any, action: Callable[[], Any]) -> Any:
        """Run ``action``; the Result says OK, or the refusal's code and reason. Never raises."""
        log = self.node.get_logger()
        try:
            action()
            response.result.result = OK
            response.result.error_message = ""
        except _Refused as exc:
            response.result.result = exc.code
            response.result.error_message = str(exc)
            log.warning(f"{name} refused: {exc}")
        except ValueError as exc:  # the node's own check (e.g. steps must be >= 1)
            response.result.result = OPERATION_FAILED
            response.result.error_message = str(exc)
            log.warning(f"{name} refused: {exc}")
        except Exception as exc:  # a callback must never raise: the node keeps serving
            response.result.result = OPERATION_FAILED
            response.result.error_message = f"internal error: {exc!r}"
            log.error(f"{name} failed: {exc!r}")
        return response

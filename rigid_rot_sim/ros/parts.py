"""The node's parts: what a :class:`~rigid_rot_sim.ros.node.SceneRun` is made of, each built from the scene.

Each part owns one concern and is built by one small factory here from the scene's settings
(:class:`~rigid_rot_sim.ros.parameters.NodeSettings`) and the run's core (the simulator, the outputs,
the run driver, the command intake). Every part says for the start-up line what it built and what it
left out (:meth:`Part.describe`) and, where it holds something, closes (``close()``, idempotent). The
command doors (:class:`~.intake.CommandDoor`: the torque inputs, the wheel input, the JointState door) also
name their subscriptions (the wrong-type watch, the recording's topics) and take listeners (the
recording hears every command as received).

The parts, in the start-up line's order: lockstep (:mod:`.lockstep`), the integrator, the outputs
(:mod:`.outputs`), the command doors (:mod:`.inputs`, :mod:`.wheel_inputs`, :mod:`.rod_inputs`,
:mod:`.joint_state_door`),
the scene's physics and sensors, the standard simulation services (:mod:`.simulation_services`), the
recording (:mod:`.recording`), the live views (:mod:`.live_views`).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol, runtime_checkable

from rclpy.node import Node
from rclpy.subscription import Subscription
from rclpy.time_source import CLOCK_TOPIC

from rigid_rot_sim.ros import parameters as params
from rigid_rot_sim.ros import simulation_services as standard_services
from rigid_rot_sim.ros.inputs import Rejections, TorqueInputs
from rigid_rot_sim.ros.intake import CommandDoor, CommandIntake
from rigid_rot_sim.ros.joint_state_door import JointStateDoor
from rigid_rot_sim.ros.lockstep import NodeLockstep, declare_lockstep_parameters, lockstep_from_parameters
from rigid_rot_sim.ros.outputs import Outputs
from rigid_rot_sim.ros.parameters import NodeSettings
from rigid_rot_sim.ros.qos import output_qos
from rigid_rot_sim.ros.rod_inputs import RodCommandInput
from rigid_rot_sim.ros.services import RunServices
from rigid_rot_sim.ros.topic_types import RivalPublisherWatch
from rigid_rot_sim.ros.wheel_inputs import WheelTorqueInput
from rigid_rot_sim.run.pacing import OutputSchedule, Pacer, RunDriver
from rigid_rot_sim.run.sensors import SensorSuite
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import OutputQos, Scene

if TYPE_CHECKING:  # imported when recording only: the mcap packages are optional at run time
    from rigid_rot_sim.ros.recording import NodeRecording


class Part(Protocol):
    """One concern of the node's run."""

    def describe(self) -> tuple[list[str], list[str]]:
        """For the start-up line: what was built, and what was left out (and why)."""
        ...


@runtime_checkable
class Closing(Protocol):
    """A part that holds something (a file, a server, an action): closed when the run ends, idempotent."""

    def close(self) -> None: ...


@dataclass
class Words:
    """A part that is only words on the start-up line: something the scene has, or a part left out."""

    built: list[str] = field(default_factory=list)
    left_out: list[str] = field(default_factory=list)

    def describe(self) -> tuple[list[str], list[str]]:
        return list(self.built), list(self.left_out)


def startup_line(head: str, parts: Iterable[Part]) -> str:
    """``head``, then what the parts built and what they left out, in one line."""
    built: list[str] = []
    left_out: list[str] = []
    for part in parts:
        part_built, part_left_out = part.describe()
        built += part_built
        left_out += part_left_out
    return f"{head}; built: {'; '.join(built)}; left out: {'; '.join(left_out) or 'nothing'}"


# ---------------------------------------------------------------------- the run's core


def settings(node: Node, scene: Scene) -> NodeSettings:
    """Declare the node's parameters (the scene's values as defaults) and read them."""
    params.declare_parameters(node, scene)
    declare_lockstep_parameters(node, scene)
    return params.read_settings(node, scene)


def simulator(settings: NodeSettings) -> Simulator:
    """The engine of the settings' scene, with the integrator, dt and torque limit of the parameters."""
    sim = Simulator(settings.scene, method=settings[params.INTEGRATOR], dt=settings[params.DT])
    sim.commands.max_torque = float(settings[params.MAX_TORQUE])
    return sim


def outputs(node: Node, settings: NodeSettings, sim: Simulator) -> Outputs:
    """The publishers of the scene's outputs, with the scene's sensor models (the run's seed) when it has any."""
    scene = settings.scene
    models = (scene.sensors.gyro, scene.sensors.star_tracker, scene.sensors.magnetometer)
    sensors = SensorSuite(scene.sensors, field=scene.orbit_field()) if any(m is not None for m in models) else None
    state_qos = output_qos(OutputQos(settings[params.QOS_RELIABILITY], settings[params.QOS_DEPTH]))
    return Outputs(node, scene, settings.rates(), state_qos, settings[params.GROUND_TRUTH_VARIANCE], sensors)


def driver(settings: NodeSettings, sim: Simulator, outputs: Outputs) -> RunDriver:
    """The run driver: the outputs' schedule, the pacer, the duration (0: unbounded)."""
    schedule = OutputSchedule.from_rates(outputs.rates, sim.clock.dt)
    pacer = Pacer(settings[params.REAL_TIME_FACTOR])
    return RunDriver(sim, schedule, pacer, settings[params.DURATION] or None, observers=[outputs])


# ---------------------------------------------------------------------- the parts


def command_doors(
    intake: CommandIntake, settings: NodeSettings, run: RunDriver, outputs: Outputs, rejections: Rejections
) -> tuple[TorqueInputs, WheelTorqueInput, RodCommandInput, JointStateDoor]:
    """The scene's command topics: the torque inputs, ``~/wheel_torque``, ``~/magnetorquer_command``, the wheels'
    JointState door."""
    sim, scene, depth = run.sim, settings.scene, settings[params.COMMAND_DEPTH]
    joint_state_topics = (settings[params.JOINT_STATE_COMMANDS], settings[params.JOINT_STATE_STATES])
    inputs = TorqueInputs(intake, sim, scene, depth, rejections)
    wheel_input = WheelTorqueInput(intake, sim, scene, depth, rejections)
    rod_input = RodCommandInput(intake, sim, scene, depth, rejections)
    door = JointStateDoor(intake, sim, scene, joint_state_topics, outputs.rates.get("wheels", 0.0), depth, rejections)
    run.observers.append(door)  # the states, at ~/wheels' steps
    return inputs, wheel_input, rod_input, door


def subscriptions(doors: Sequence[CommandDoor]) -> list[Subscription]:
    """Every command subscription of the doors."""
    return [subscription for door in doors for subscription in door.subscriptions]


def lockstep(node: Node, settings: NodeSettings, run: RunDriver) -> NodeLockstep | None:
    """The lockstep turns of the scene or the ``lockstep.*`` parameters; None without."""
    spec = lockstep_from_parameters(node, settings.scene, run.sim.clock.dt)
    return None if spec is None else NodeLockstep(node, spec, run)


@dataclass
class OutputsPart:
    """The outputs as a part: their rates said against the run's step (a rate above it is one per step)."""

    outputs: Outputs
    sim: Simulator

    def describe(self) -> tuple[list[str], list[str]]:
        return self.outputs.describe(self.sim.clock.dt)


#: The end of the warning about another node on /clock: what its consumers see, and the fix.
CLOCK_RIVAL_ADVICE = (
    "every use_sim_time node sees two timelines and its time jumps back (a tf2 buffer is cleared each time); "
    "keep one /clock: rates.clock:=0 on the others, or remap one (-r /clock:=/other/clock)"
)


def clock_watch(node: Node, outputs: Outputs) -> RivalPublisherWatch | None:
    """Another node publishing /clock beside this one's, named in the log (None: this node publishes no /clock)."""
    return RivalPublisherWatch(node, CLOCK_TOPIC, CLOCK_RIVAL_ADVICE) if "clock" in outputs.publishers else None


def lockstep_part(lockstep: NodeLockstep | None) -> Part:
    return lockstep if lockstep is not None else Words(left_out=["lockstep (commands act when they arrive)"])


def integrator_part(settings: NodeSettings, sim: Simulator) -> Part:
    auto = ", auto" if settings[params.INTEGRATOR] == "auto" else ""
    return Words([f"integrator {sim.stepper.method} (dt {sim.clock.dt:g} s{auto})"])


def physics_part(scene: Scene, sensors: SensorSuite | None) -> Part:
    """The scene's sensor models, torque schedules and gravity, as words."""
    words = Words()
    if sensors is None:
        words.left_out.append("sensor models (~/imu, if asked for, is ideal; no ~/star_tracker)")
    else:
        drawn = "" if scene.sensors.seed is not None else ", drawn"
        words.built.append(f"sensors {', '.join(sensors.names)} (seed {sensors.seed}{drawn})")
    if scene.schedules:
        words.built.append(f"{len(scene.schedules)} torque schedule(s)")
    if scene.gravity is None:
        words.left_out.append("gravity (no potential energy, no ~/top_state)")
    else:
        words.built.append(f"gravity {scene.gravity.acceleration:g} m/s^2 about the pivot")
    return words


def simulation_services(
    node: Node, settings: NodeSettings, services: RunServices
) -> standard_services.SimulationServices | None:
    """The standard simulation_interfaces services, where the package is installed."""
    if not standard_services.AVAILABLE:
        return None
    return standard_services.SimulationServices(node, services, settings[params.SIMULATION_INTERFACES_NAMESPACE])


def simulation_services_part(services: standard_services.SimulationServices | None) -> Part:
    return (
        services if services is not None else Words(left_out=["simulation_interfaces services (package not installed)"])
    )


def recording(
    node: Node, settings: NodeSettings, sim: Simulator, outputs: Outputs, doors: Sequence[CommandDoor]
) -> NodeRecording | None:
    """The recording (the ``record_path`` parameter), attached to the run; None (error logged) when it
    cannot start: the run goes on."""
    path, log_time = settings[params.RECORD_PATH], settings[params.RECORD_LOG_TIME]
    if not path:
        return None
    try:
        from rigid_rot_sim.ros.recording import NodeRecording  # imported only when recording
    except ImportError as exc:  # the mcap packages are optional at run time
        missing = (exc.name or "").split(".")[0] or str(exc)
        node.get_logger().error(f"recording disabled: {missing} is not installed (pip install mcap mcap-ros2-support)")
        return None
    return NodeRecording.attach(node, sim, outputs, doors, path, log_time)


def recording_part(settings: NodeSettings, recording: NodeRecording | None) -> Part:
    if recording is not None:
        return recording
    if settings[params.RECORD_PATH]:
        return Words(["no recording (see the error above)"])
    return Words(left_out=["recorder (nothing recorded)"])


__all__ = [
    "Closing",
    "CommandDoor",
    "Part",
    "Words",
    "command_doors",
    "driver",
    "integrator_part",
    "lockstep",
    "lockstep_part",
    "outputs",
    "physics_part",
    "recording",
    "recording_part",
    "settings",
    "simulation_services",
    "simulation_services_part",
    "simulator",
    "startup_line",
    "subscriptions",
]

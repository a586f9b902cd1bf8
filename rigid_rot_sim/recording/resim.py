"""Re-simulate a recorded run without ROS and compare the states with the recorded ones.

The bag holds the scene as given, the integrator actually used (``auto`` resolved), and
the simulation event log (:mod:`.events`: every torque command with the step at which it
arrived and its effective sim time, every service call that changed the state). Replaying
the events through :class:`rigid_rot_sim.run.simulator.Simulator` in recorded order,
advancing to the recorded step before each, rebuilds the run: with the same integrator
the states are bit-identical to the recorded ones; with another integrator the report
shows what that integrator changes on this very run.

Sensor readings (``~/imu`` of a scene with ``sensors.gyro``, ``~/star_tracker``, ``~/magnetometer``) are drawn
again from the recorded seed (the ``sensors`` metadata record), one per recorded message
in file order, at the recorded message's step (:class:`~rigid_rot_sim.run.sensors.SensorSuite`),
and compared bit for bit: the re-simulation is BIT-EXACT only when they agree too.

The reaction wheels' states (``~/wheels``, sensor_msgs/JointState: angle, speed and motor torque
per wheel) are compared bit for bit at each recorded message's step in the same way: the wheel
angles drive nothing, so neither the body's states nor the run digest (t, q, omega) would notice
a wheel angle that differs.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.message_fields import quaternion_to_array, time_to_seconds, vector3_to_array
from rigid_rot_sim.recording.events import EVENT_TYPE, SimEvent, decode_event
from rigid_rot_sim.recording.provenance import core_fingerprint
from rigid_rot_sim.recording.reader import BagReader
from rigid_rot_sim.run.digest import format_digest
from rigid_rot_sim.run.sensors import SensorSuite
from rigid_rot_sim.run.simulator import Simulator, StateSnapshot
from rigid_rot_sim.scene.features import refuse_unhonoured
from rigid_rot_sim.scene.scene import parse_scene_text

STATE_TYPE = "rigid_rot_msgs/msg/RigidBodyState"
WHEELS_TYPE = "sensor_msgs/msg/JointState"
#: Sensor outputs: role -> (message type, the sensor's field of the scene's sensors section).
SENSOR_TYPES = {
    "imu": ("sensor_msgs/msg/Imu", "gyro"),
    "star_tracker": ("geometry_msgs/msg/PoseWithCovarianceStamped", "star_tracker"),
    "magnetometer": ("sensor_msgs/msg/MagneticField", "magnetometer"),
}

_VECTOR_FIELDS = (
    "angular_velocity_body",
    "angular_velocity_world",
    "angular_momentum_body",
    "angular_momentum_world",
    "torque_body",
)
_SCALAR_FIELDS = ("kinetic_energy", "potential_energy", "energy_drift", "angular_momentum_drift")


@dataclass(frozen=True)
class ResimReport:
    """Outcome of :func:`resimulate`.

    Deviations are maxima over the compared states: attitude as the rotation angle
    between recorded and re-simulated attitude (rad), ω (body frame, rad/s) and L (world
    frame, kg*m^2/s) as Euclidean norms of the difference. ``identical`` is True when
    every field of every state is bit-for-bit equal.
    """

    path: str
    method: str
    recorded_method: str
    dt: float
    states: int
    events: int
    duration: float
    max_attitude_error: float
    max_omega_error: float
    max_momentum_error: float
    max_energy_error: float
    identical: bool
    first_difference_t: float | None
    core_changed: bool | None = None
    #: The run digest (:mod:`rigid_rot_sim.run.digest`) the re-simulation reached at the last compared
    #: state, and the one recorded there (the state's ``digest`` field); None without states or field.
    digest: int | None = None
    recorded_digest: int | None = None

    @property
    def digest_verdict(self) -> str:
        """``equal`` or ``different`` (the digests at the last state), or why there is nothing to compare."""
        if self.digest is None:
            return "no states to compare"
        if self.recorded_digest is None:
            return "not recorded (a recording made before the run digest)"
        return "equal" if self.digest == self.recorded_digest else "different"

    sensor_readings: int = 0
    sensor_mismatches: int = 0
    #: ``~/wheels`` messages compared (angle, speed, motor torque of every wheel) and how many differ.
    wheel_states: int = 0
    wheel_mismatches: int = 0

    @property
    def verdict(self) -> str:
        """One line: reproduced bit for bit, or how far the states differ."""
        if self.states == 0:
            return "NOTHING TO COMPARE: the recording holds no state messages"
        if self.identical:
            readings = f" and {self.sensor_readings} sensor readings" if self.sensor_readings else ""
            wheels = f" and {self.wheel_states} wheel states" if self.wheel_states else ""
            return f"BIT-EXACT: all {self.states} states{readings}{wheels} reproduced bit for bit"
        if self.wheel_mismatches and not self.sensor_mismatches and self.max_attitude_error == 0.0:
            return (
                f"MISMATCH: {self.wheel_mismatches} of {self.wheel_states} wheel states differ (the body states agree)"
            )
        if self.sensor_mismatches and self.max_attitude_error == self.max_omega_error == 0.0:
            return (
                f"MISMATCH: {self.sensor_mismatches} of {self.sensor_readings} sensor readings differ "
                "(the states agree; a different numpy draws different noise?)"
            )
        same = self.method == self.recorded_method
        if same and self.core_changed:
            label = "DIFFERS (same integrator, but the numerical core changed since the recording)"
        elif same and self.core_changed is None:
            label = "MISMATCH (same integrator; the recording does not say which core made it)"
        elif same:
            label = "MISMATCH (same integrator and core, expected bit-exact)"
        else:
            label = f"DIFFERS ({self.method} vs recorded {self.recorded_method})"
        return (
            f"{label}: max attitude {self.max_attitude_error:.3e} rad, "
            f"max |dω| {self.max_omega_error:.3e} rad/s, max |dL| {self.max_momentum_error:.3e} kg*m^2/s"
        )

    def format(self) -> str:
        """A short multi-line report for the terminal."""
        lines = [
            self.path,
            f"  integrator: {self.method} (recorded: {self.recorded_method}), dt = {self.dt:g} s",
        ]
        if self.core_changed:
            lines.append("  note: rigid_rot_sim.core changed since the recording (source fingerprint differs)")
        lines += [
            f"  compared {self.states} states over {self.duration:.6g} s of sim time, replayed {self.events} events",
            f"  max attitude deviation  {self.max_attitude_error:.3e} rad",
            f"  max |ω| deviation       {self.max_omega_error:.3e} rad/s (body frame)",
            f"  max |L| deviation       {self.max_momentum_error:.3e} kg*m^2/s (world frame)",
            f"  max energy deviation    {self.max_energy_error:.3e} J",
        ]
        if self.sensor_readings:
            lines.append(f"  sensor readings         {self.sensor_readings} redrawn, {self.sensor_mismatches} differ")
        if self.wheel_states:
            lines.append(f"  wheel states            {self.wheel_states} compared, {self.wheel_mismatches} differ")
        if self.first_difference_t is not None:
            lines.append(f"  first difference at t = {self.first_difference_t:.9g} s")
        if self.digest is not None:
            recorded = "?" if self.recorded_digest is None else format_digest(self.recorded_digest)
            lines.append(f"  run digest {format_digest(self.digest)}, recorded {recorded}: {self.digest_verdict}")
        lines.append(f"  verdict: {self.verdict}")
        return "\n".join(lines)


def attitude_angle(q_a: np.ndarray, q_b: np.ndarray) -> float:
    """Rotation angle (rad, in [0, pi]) between two unit quaternions (x, y, z, w).

    Computed as 2 atan2(|v|, |w|) of q_a^-1 q_b, accurate for tiny angles too (unlike acos).
    The formula of :func:`rigid_rot_sim.analysis.metrics.attitude_error_angle` without its
    normalisation: the recorded and re-simulated quaternions are compared as they are
    (and recording sits below analysis, which imports it).
    """
    if np.array_equal(q_a, q_b):
        return 0.0  # identical attitudes: exactly 0, whatever the rounding of the product
    dx, dy, dz, dw = quat.multiply(quat.conjugate(q_a), q_b)
    return 2.0 * math.atan2(math.sqrt(dx * dx + dy * dy + dz * dz), abs(dw))


def _apply(sim: Simulator, event: SimEvent, override_method: str | None) -> None:
    kind = event.kind
    if kind == "torque":
        sim.submit_torque(
            event.values["source"],
            event.vector("torque"),
            event.values["frame"],
            event.number("effective_time"),
            receipt_time=event.optional_float("receipt_time"),
            stamp=event.optional_float("stamp"),
        )
    elif kind == "wheel_torque":  # the torques as clamped then: they clamp to themselves
        torques = event.vector("torques", len(sim.scene.spacecraft.wheels))
        sim.submit_wheel_torques(event.values["source"], torques, effective_time=event.number("effective_time"))
    elif kind == "rod_dipoles":  # the dipoles as clamped then: they clamp to themselves
        dipoles = event.vector("dipoles", len(sim.scene.spacecraft.rods))
        sim.submit_rod_dipoles(event.values["source"], dipoles, effective_time=event.number("effective_time"))
    elif kind == "apply_torque":
        frame_id = sim.frames.body if event.values["frame"] == "body" else sim.frames.world
        sim.apply_torque(
            event.vector("torque"), frame_id, event.number("duration"), effective_time=event.number("effective_time")
        )
    elif kind == "set_state":
        sim.set_state(event.vector("orientation", 4), event.vector("angular_velocity"))
    elif kind == "reset":
        sim.reset()
    elif kind == "integrator":
        options = json.loads(event.values.get("options") or "{}")
        method = event.values["method"] if override_method is None else override_method
        sim.set_integrator(method, event.number("dt"), options if override_method is None else {})
    elif kind == "lockstep_timeout":
        pass  # a lockstep turn that timed out: the run paused or held, the states do not depend on it
    else:
        raise ValueError(f"unknown event kind {kind!r} at step {event.step}")


def resimulate(path: str | os.PathLike[str], method: str | None = None) -> ResimReport:
    """Re-run the recording at ``path`` (optionally with another integrator) and compare.

    ValueError when the file lacks what a re-simulation needs (scene, integrator
    metadata, the event log).
    """
    reader = BagReader(path)
    scene_record = reader.metadata.get("scene")
    integrator_record = reader.metadata.get("integrator")
    if not scene_record or "text" not in scene_record:
        raise ValueError(f"{path}: no 'scene' metadata record: not recorded by rigid_rot_sim")
    if not integrator_record:
        raise ValueError(f"{path}: no 'integrator' metadata record")
    scene = parse_scene_text(scene_record["text"], source=scene_record.get("file", "<recorded scene>"))
    refuse_unhonoured(scene, "resim")  # scene/features.py: what a re-simulation runs
    recorded_method = integrator_record["method"]
    dt = float(integrator_record["dt"])
    options = json.loads(integrator_record.get("options") or "{}")
    chosen = recorded_method if method in (None, recorded_method) else method
    sim = Simulator(scene, method=chosen, dt=dt, options=options if chosen == recorded_method else {})
    override = None if chosen == recorded_method else chosen

    state_topic = reader.find_topic("state", STATE_TYPE)
    events_topic = reader.find_topic("events", EVENT_TYPE)
    if events_topic is None:
        raise ValueError(f"{path}: no simulation event log (~/sim_events) in the recording")
    sensors, sensor_topics = _sensors(reader, scene, path)
    wheels_topic = reader.find_topic("wheels", WHEELS_TYPE) if scene.spacecraft.wheels else None
    topics = [events_topic] + ([state_topic] if state_topic else []) + list(sensor_topics)
    topics += [wheels_topic] if wheels_topic else []
    readings = mismatches = wheel_states = wheel_mismatches = 0

    states = events = 0
    max_att = max_omega = max_l = max_e = 0.0
    identical = True
    first_difference: float | None = None
    t_first: float | None = None
    t_last = 0.0
    digest = recorded_digest = None
    for message, decoded in reader.decoded(topics):
        if message.topic == events_topic:
            event = decode_event(decoded)
            if event.step > sim.clock.k:
                sim.advance_to(event.step)
            _apply(sim, event, override)
            events += 1
            continue
        t = time_to_seconds(decoded.header.stamp)
        k = sim.clock.k + round((t - sim.clock.t) / sim.clock.dt)
        sim.advance_to(k)
        snapshot = sim.snapshot()
        if message.topic in sensor_topics:
            readings += 1
            if not _same_reading(sensor_topics[message.topic], sensors, decoded, snapshot):
                mismatches += 1
                if identical:
                    identical, first_difference = False, t
            continue
        if message.topic == wheels_topic:
            wheel_states += 1
            if not _same_wheels(decoded, snapshot):
                wheel_mismatches += 1
                if identical:
                    identical, first_difference = False, t
            continue
        differs, errors = _compare(decoded, snapshot)
        recorded_digest = getattr(decoded, "digest", None)  # absent before the digest field existed
        if recorded_digest is not None:
            recorded_digest = int(recorded_digest)
            differs = differs or recorded_digest != snapshot.digest
        digest = snapshot.digest
        states += 1
        t_first = t if t_first is None else t_first
        t_last = t
        max_att = max(max_att, errors[0])
        max_omega = max(max_omega, errors[1])
        max_l = max(max_l, errors[2])
        max_e = max(max_e, errors[3])
        if differs and identical:
            identical = False
            first_difference = t
    recorded_core = reader.metadata.get("versions", {}).get("rigid_rot_sim.core_sha256")
    return ResimReport(
        core_changed=None if recorded_core is None else recorded_core != core_fingerprint(),
        path=str(path),
        method=sim.stepper.method,
        recorded_method=recorded_method,
        dt=dt,
        states=states,
        events=events,
        duration=0.0 if t_first is None or t_last is None else t_last - t_first,
        max_attitude_error=max_att,
        max_omega_error=max_omega,
        max_momentum_error=max_l,
        max_energy_error=max_e,
        identical=identical and states > 0,
        first_difference_t=first_difference,
        digest=digest,
        recorded_digest=recorded_digest,
        sensor_readings=readings,
        sensor_mismatches=mismatches,
        wheel_states=wheel_states,
        wheel_mismatches=wheel_mismatches,
    )


def _sensors(reader: BagReader, scene: Any, path: Any) -> tuple[SensorSuite | None, dict[str, str]]:
    """The run's sensors with the recorded seed, and their recorded topics (topic -> role)."""
    models = scene.sensors
    roles = [role for role, (_, field) in SENSOR_TYPES.items() if getattr(models, field) is not None]
    if not roles:
        return None, {}
    recorded = reader.metadata.get("sensors", {})
    seed = json.loads(recorded["seed"]) if "seed" in recorded else models.seed
    if seed is None:
        raise ValueError(f"{path}: the scene has sensors but the recording holds no seed ('sensors' metadata)")
    topics = {}
    for role in roles:
        topic = reader.find_topic(role, SENSOR_TYPES[role][0])
        if topic is not None:
            topics[topic] = role
    return SensorSuite(models, seed=seed, field=scene.orbit_field()), topics


def _same_reading(role: str, sensors: Any, recorded: Any, snapshot: StateSnapshot) -> bool:
    """Draw the next reading of the sensor behind ``role`` and compare it with the recorded message."""
    if role == "imu":
        return bool(np.array_equal(vector3_to_array(recorded.angular_velocity), sensors.read_gyro(snapshot)))
    if role == "magnetometer":
        return bool(np.array_equal(vector3_to_array(recorded.magnetic_field), sensors.read_magnetometer(snapshot)))
    attitude = quaternion_to_array(recorded.pose.pose.orientation)
    return bool(np.array_equal(attitude, sensors.read_star_tracker(snapshot)))


def _same_wheels(recorded: Any, snapshot: StateSnapshot) -> bool:
    """A recorded ``~/wheels`` message against the re-simulated wheels, bit for bit.

    A recording made before wheel angles were simulated has no positions: those are not compared.
    """
    fields = [(recorded.velocity, snapshot.wheel_speeds), (recorded.effort, snapshot.wheel_torques)]
    if len(recorded.position):
        fields.append((recorded.position, snapshot.wheel_angles))
    return list(recorded.name) == list(snapshot.wheel_names or ()) and all(
        np.array_equal(np.asarray(given, dtype=float), np.asarray(mine, dtype=float)) for given, mine in fields
    )


def _compare(recorded: Any, snapshot: StateSnapshot) -> tuple[bool, tuple[float, float, float, float]]:
    q_rec = quaternion_to_array(recorded.orientation)
    differs = not np.array_equal(q_rec, snapshot.orientation)
    for name in _VECTOR_FIELDS:
        differs = differs or not np.array_equal(vector3_to_array(getattr(recorded, name)), getattr(snapshot, name))
    for name in _SCALAR_FIELDS:
        differs = differs or float(getattr(recorded, name)) != float(getattr(snapshot, name))
    omega = float(np.linalg.norm(vector3_to_array(recorded.angular_velocity_body) - snapshot.angular_velocity_body))
    momentum = float(
        np.linalg.norm(vector3_to_array(recorded.angular_momentum_world) - snapshot.angular_momentum_world)
    )
    energy = abs(float(recorded.kinetic_energy) + float(recorded.potential_energy) - snapshot.energy)
    return differs, (attitude_angle(q_rec, snapshot.orientation), omega, momentum, energy)

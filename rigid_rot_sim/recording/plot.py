"""Pictures of a recorded run: PNGs a person reads at a glance (matplotlib, Agg backend).

* ``omega.png``: the body-frame angular velocity components and |ω| over sim time;
* ``drift.png``: relative change of the total energy and of |L| since the first state;
  for a free body both measure the integrator's error, with torque they show the work
  and the angular impulse the torques delivered;
* ``torque.png``: the torque applied (body frame, total over each step), with the
  effective times of the recorded torque commands;
* ``polhode.png``: the path of ω on the energy ellipsoid ω·Iω = 2T in the principal
  frame (the polhode), coloured by time;
* ``sensors.png`` (runs with sensor models): the gyro's reading minus the true ω and the
  star tracker's attitude error about the body axes, against their 1-sigma noise;
* ``wheels.png`` (runs with reaction wheels, ``~/wheels`` recorded): each wheel's speed relative
  to the body and its motor torque over sim time.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import numpy as np

from rigid_rot_sim.message_fields import quaternion_to_array, time_to_seconds, vector3_to_array
from rigid_rot_sim.recording.events import EVENT_TYPE, decode_event
from rigid_rot_sim.recording.reader import BagReader
from rigid_rot_sim.recording.resim import SENSOR_TYPES, STATE_TYPE
from rigid_rot_sim.scene.scene import parse_scene_text

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

#: The type of the recorded ~/wheels (the node's JointState of its reaction wheels).
WHEELS_TYPE = "sensor_msgs/msg/JointState"

_AXIS_COLOURS = ("tab:red", "tab:green", "tab:blue")


@dataclass(frozen=True)
class StateSeries:
    """The recorded states as arrays over time (sim time, s)."""

    t: np.ndarray
    omega_body: np.ndarray
    momentum_body: np.ndarray
    momentum_world: np.ndarray
    torque_body: np.ndarray
    energy: np.ndarray


def load_states(reader: BagReader) -> StateSeries:
    """Every RigidBodyState of the recording, in log order; ValueError if there is none."""
    topic = reader.find_topic("state", STATE_TYPE)
    if topic is None:
        raise ValueError(f"{reader.path}: no {STATE_TYPE} topic recorded: nothing to plot")
    rows = []
    for _, msg in reader.decoded([topic]):
        t = time_to_seconds(msg.header.stamp)
        vectors = [msg.angular_velocity_body, msg.angular_momentum_body, msg.angular_momentum_world, msg.torque_body]
        rows.append([t, *(c for v in vectors for c in (v.x, v.y, v.z)), msg.kinetic_energy + msg.potential_energy])
    if not rows:
        raise ValueError(f"{reader.path}: topic {topic} holds no messages: nothing to plot")
    data = np.array(rows, dtype=float)
    return StateSeries(data[:, 0], data[:, 1:4], data[:, 4:7], data[:, 7:10], data[:, 10:13], data[:, 13])


def principal_frame(reader: BagReader, series: StateSeries) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments (ascending, kg*m^2) and the matrix whose columns are the principal axes.

    From the recorded scene when present; otherwise fitted to the recorded pairs
    L_body = I ω (least squares over all states), which needs ω to span three directions.
    """
    scene = reader.metadata.get("scene", {})
    if "text" in scene:
        inertia = parse_scene_text(scene["text"], source=scene.get("file", "<recorded scene>")).body.inertia_array
        tensor = np.asarray(inertia, dtype=float)
        tensor = np.diag(tensor) if tensor.ndim == 1 else tensor
    else:
        w, big_l = series.omega_body, series.momentum_body
        # unknowns (Ixx, Iyy, Izz, Ixy, Ixz, Iyz): L = I w, three equations per state
        rows = []
        for wx, wy, wz in w:
            rows += [[wx, 0, 0, wy, wz, 0], [0, wy, 0, wx, 0, wz], [0, 0, wz, 0, wx, wy]]
        sol, *_ = np.linalg.lstsq(np.array(rows), big_l.reshape(-1), rcond=None)
        ixx, iyy, izz, ixy, ixz, iyz = sol
        tensor = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    moments, axes = np.linalg.eigh(tensor)
    # eigenvectors come with arbitrary signs: make each axis point along its largest body component
    signs = np.sign(axes[np.argmax(np.abs(axes), axis=0), np.arange(3)])
    return moments, axes * signs


def _title(reader: BagReader, what: str) -> str:
    scene = reader.metadata.get("scene", {}).get("file", "")
    method = reader.metadata.get("integrator", {}).get("method", "")
    name = Path(scene).stem if scene else reader.path.stem
    return f"{what} - {name}" + (f" ({method})" if method else "")


def plot_run(path: str | os.PathLike[str], out_dir: str | os.PathLike[str] | None = None) -> list[Path]:
    """Write the four PNGs for the recording at ``path``; returns their paths.

    ``out_dir`` defaults to ``<recording stem>_plots`` next to the recording.
    """
    reader = BagReader(path)
    series = load_states(reader)
    out = Path(out_dir) if out_dir is not None else reader.path.with_name(reader.path.stem + "_plots")
    out.mkdir(parents=True, exist_ok=True)
    t = series.t
    written: list[Path] = []

    def save(fig, name: str) -> None:
        if fig.get_layout_engine() is None:
            fig.tight_layout()
        target = out / name
        fig.savefig(target, dpi=110)
        plt.close(fig)
        written.append(target)

    # ω components
    fig, ax = plt.subplots(figsize=(9, 4.5))
    for i, axis in enumerate("xyz"):
        ax.plot(t, series.omega_body[:, i], color=_AXIS_COLOURS[i], label=f"ω_{axis}")
    ax.plot(t, np.linalg.norm(series.omega_body, axis=1), color="black", linestyle="--", linewidth=1, label="|ω|")
    ax.set(
        xlabel="sim time (s)", ylabel="angular velocity, body frame (rad/s)", title=_title(reader, "Angular velocity")
    )
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", ncols=4)
    save(fig, "omega.png")

    # relative drift of energy and |L| (absolute values when the run starts at rest)
    energy0 = series.energy[0]
    l_norm = np.linalg.norm(series.momentum_world, axis=1)
    driven = bool(np.any(series.torque_body != 0.0))
    note = (
        "torque applied: changes include the torques' work and impulse"
        if driven
        else "torque-free: any change is integrator error"
    )
    fig, ax = plt.subplots(figsize=(9, 4.5))
    if energy0 != 0.0 and l_norm[0] != 0.0:
        energy_rel = (series.energy - energy0) / abs(energy0)
        l_rel = (l_norm - l_norm[0]) / l_norm[0]
        ax.plot(t, energy_rel, color="tab:orange", label=f"(E - E0)/|E0|   max |.| = {np.max(np.abs(energy_rel)):.2e}")
        ax.plot(t, l_rel, color="tab:purple", label=f"(|L| - |L0|)/|L0|   max |.| = {np.max(np.abs(l_rel)):.2e}")
        ax.axhline(0.0, color="black", linewidth=0.8)
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
        ax.set(ylabel="relative change (1)", title=_title(reader, "Energy and |L| drift") + f"\n{note}")
        ax.legend(loc="best")
    else:  # a relative change from zero is undefined: show the quantities themselves
        ax.plot(t, series.energy, color="tab:orange", label="E (J)")
        ax.set_ylabel("energy E (J)", color="tab:orange")
        twin = ax.twinx()
        twin.plot(t, l_norm, color="tab:purple", label="|L| (kg*m^2/s)")
        twin.set_ylabel("|L| (kg*m^2/s)", color="tab:purple")
        ax.set_title(
            _title(reader, "Energy and |L|") + "\nstarts at rest (relative change undefined); " + note.split(":")[0]
        )
        ax.legend(handles=ax.get_lines() + twin.get_lines(), loc="best")
    ax.set_xlabel("sim time (s)")
    ax.grid(True, alpha=0.3)
    save(fig, "drift.png")

    # torque applied, with command times
    fig, ax = plt.subplots(figsize=(9, 4.5))
    for i, axis in enumerate("xyz"):
        ax.step(t, series.torque_body[:, i], where="pre", color=_AXIS_COLOURS[i], label=f"τ_{axis}")
    command_times = _command_times(reader)
    for j, effective in enumerate(command_times):
        ax.axvline(
            effective, color="grey", linewidth=0.6, linestyle=":", label="command takes effect" if j == 0 else None
        )
    ax.set(
        xlabel="sim time (s)",
        ylabel="torque, body frame (N*m)",
        title=_title(reader, "Torque applied") + f"\n{len(command_times)} torque commands recorded",
    )
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best")
    save(fig, "torque.png")

    # polhode on the energy ellipsoid, principal frame
    moments, axes = principal_frame(reader, series)
    omega_p = series.omega_body @ axes  # components along the principal axes
    energy_twice = float(np.einsum("ij,j,ij->i", omega_p[:1], moments, omega_p[:1])[0])
    fig = plt.figure(figsize=(13, 6.5), layout="constrained")
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    if energy_twice > 0.0:
        u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 40), np.linspace(0, np.pi, 20))
        a, b, c = np.sqrt(energy_twice / moments)
        ax3.plot_wireframe(
            a * np.cos(u) * np.sin(v), b * np.sin(u) * np.sin(v), c * np.cos(v), color="lightgrey", linewidth=0.5
        )
    points = ax3.scatter(omega_p[:, 0], omega_p[:, 1], omega_p[:, 2], c=t, cmap="viridis", s=4)
    ax3.plot(omega_p[:, 0], omega_p[:, 1], omega_p[:, 2], color="black", linewidth=0.4, alpha=0.5)
    span = float(np.max(np.abs(omega_p))) * 1.1 or 1.0
    if energy_twice > 0.0:
        span = max(span, float(np.max(np.sqrt(energy_twice / moments))) * 1.05)
    ax3.set(
        xlim=(-span, span),
        ylim=(-span, span),
        zlim=(-span, span),
        xlabel="ω1 (rad/s)",
        ylabel="ω2 (rad/s)",
        zlabel="ω3 (rad/s)",
    )
    ax3.set_box_aspect((1, 1, 1), zoom=0.9)  # room for the z label inside the axes (it met the next plot's)
    ax3.set_title(
        "on the energy ellipsoid ω·Iω = 2T0, I = "
        + ", ".join(f"{m:.4g}" for m in moments)
        + " kg*m^2"
        + ("\n(initial energy; torques move ω off it)" if driven else "")
    )
    # the same path seen along the principal axis ω stays closest to: the polhode's shape
    along = int(np.argmax(np.mean(np.abs(omega_p), axis=0)))
    i, j = [k for k in range(3) if k != along]
    ax2 = fig.add_subplot(1, 2, 2)
    ax2.scatter(omega_p[:, i], omega_p[:, j], c=t, cmap="viridis", s=4)
    ax2.plot(omega_p[:, i], omega_p[:, j], color="black", linewidth=0.4, alpha=0.5)
    ax2.plot(omega_p[0, i], omega_p[0, j], marker="o", color="tab:red", label="start")
    ax2.plot(omega_p[-1, i], omega_p[-1, j], marker="s", color="tab:blue", label="end")
    ax2.set_aspect("equal", adjustable="datalim")
    ax2.set(
        xlabel=f"ω{i + 1} (rad/s)",
        ylabel=f"ω{j + 1} (rad/s)",
        title=f"seen along principal axis {along + 1} (I{along + 1} = {moments[along]:.4g} kg*m^2)",
    )
    ax2.grid(True, alpha=0.3)
    ax2.legend(loc="best")
    fig.colorbar(points, ax=ax2, shrink=0.8, label="sim time (s)")
    fig.suptitle(_title(reader, "Polhode: path of ω in the principal frame"))
    save(fig, "polhode.png")
    figure = _sensor_errors(reader)
    if figure is not None:
        save(figure, "sensors.png")
    figure = wheel_figure(reader)
    if figure is not None:
        save(figure, "wheels.png")
    return written


def wheel_figure(reader: BagReader):
    """The reaction wheels' speeds and motor torques over sim time (the recorded ~/wheels); None without them."""
    topic = reader.find_topic("wheels", WHEELS_TYPE)
    if topic is None:
        return None
    t: list[float] = []
    speeds: list[list[float]] = []
    torques: list[list[float]] = []
    names: list[str] = []
    for _, msg in reader.decoded([topic]):
        names = list(msg.name) or names
        t.append(time_to_seconds(msg.header.stamp))
        speeds.append(list(msg.velocity))
        torques.append(list(msg.effort))
    if not t or not names:
        return None
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True)
    for i, name in enumerate(names):
        top.plot(t, [row[i] if i < len(row) else np.nan for row in speeds], label=name)
        bottom.plot(t, [row[i] if i < len(row) else np.nan for row in torques], label=name)
    top.set(ylabel="wheel speed, relative to the body (rad/s)", title=_title(reader, "Reaction wheels"))
    bottom.set(xlabel="sim time (s)", ylabel="motor torque (N*m)")
    for ax in (top, bottom):
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best")
    return fig


def _sensor_errors(reader: BagReader):
    """The sensors' errors against the recorded states at the same stamps; None without sensor models."""
    scene = reader.metadata.get("scene", {})
    if "text" not in scene:
        return None
    models = parse_scene_text(scene["text"], source=scene.get("file", "<recorded scene>")).sensors
    topics = {
        role: reader.find_topic(role, SENSOR_TYPES[role][0])
        for role, (_, field) in SENSOR_TYPES.items()
        if getattr(models, field) is not None
    }
    found = {role: topic for role, topic in topics.items() if topic is not None}
    state_topic = reader.find_topic("state", STATE_TYPE)
    if not found or state_topic is None:
        return None
    truth = {time_to_seconds(m.header.stamp): m for _, m in reader.decoded([state_topic])}
    fig, axes = plt.subplots(len(found), 1, figsize=(9, 3.6 * len(found)), squeeze=False)
    for ax, (role, topic) in zip(axes[:, 0], found.items(), strict=True):
        rows = []
        for _, msg in reader.decoded([topic]):
            state = truth.get(time_to_seconds(msg.header.stamp))
            if state is None:
                continue  # compared only where a state of the same instant was recorded
            if role == "imu":
                error = vector3_to_array(msg.angular_velocity) - vector3_to_array(state.angular_velocity_body)
            else:  # body-frame error rotation q^-1 q_m, as a rotation vector
                error = _rotation_vector(
                    quaternion_to_array(state.orientation), quaternion_to_array(msg.pose.pose.orientation)
                )
            rows.append([time_to_seconds(msg.header.stamp), *error])
        data = np.array(rows).reshape(-1, 4)
        for i, axis in enumerate("xyz"):
            ax.plot(data[:, 0], data[:, i + 1], ".", markersize=2, color=_AXIS_COLOURS[i], label=axis)
        if role == "imu":
            assert models.gyro is not None  # a topic is found only for a sensor the scene names
            sigma = np.full(3, np.sqrt(models.gyro.reading_variance))
            note = "dashed: 1 sigma beyond the constant biases"
            ax.set(ylabel="reading - true ω (rad/s)", title=f"Gyro error ({len(data)} readings at state stamps)")
        else:
            assert models.star_tracker is not None
            sigma = np.asarray(models.star_tracker.noise_equivalent_angle)
            note = "dashed: noise equivalent angle"
            ax.set(
                ylabel="attitude error, body axes (rad)",
                title=f"Star tracker error ({len(data)} solutions at state stamps)",
            )
        for i in range(3):
            ax.axhline(sigma[i], color=_AXIS_COLOURS[i], linewidth=0.6, linestyle="--")
            ax.axhline(-sigma[i], color=_AXIS_COLOURS[i], linewidth=0.6, linestyle="--")
        ax.set_xlabel("sim time (s)")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", ncols=3, title=note)
    fig.suptitle(_title(reader, "Sensor errors"))
    return fig


def _rotation_vector(q_true: np.ndarray, q_measured: np.ndarray) -> np.ndarray:
    """Rotation vector (rad) of q_true^-1 q_measured (both x, y, z, w): the error about the body axes."""
    from scipy.spatial.transform import Rotation

    return (Rotation.from_quat(q_true).inv() * Rotation.from_quat(q_measured)).as_rotvec()


def _command_times(reader: BagReader) -> list[float]:
    topic = reader.find_topic("events", EVENT_TYPE)
    if topic is None:
        return []
    times = []
    for _, status in reader.decoded([topic]):
        event = decode_event(status)
        if event.kind in ("torque", "apply_torque"):
            times.append(event.number("effective_time"))
    return times

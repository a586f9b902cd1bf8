"""Re-simulation from a recording: bit-exact with the recorded integrator, a report otherwise."""

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rigid_rot_msgs.msg")
from geometry_msgs.msg import WrenchStamped

from rigid_rot_msgs.msg import RigidBodyState
from rigid_rot_sim import conversions
from rigid_rot_sim.recording.resim import attitude_angle, resimulate
from rigid_rot_sim.recording.session import RunRecorder
from rigid_rot_sim.ros.recording import NodeRecording
from rigid_rot_sim.run.simulator import CommandRejected, Simulator
from rigid_rot_sim.scene.scene import load_scene

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"


def record_like_the_node(
    path: Path, scene_name: str, steps: int, publish_every: int, commands: dict, method="rk4", log_time="sim"
):
    """Drive a Simulator as the node does (advance, publish, receive commands) and record it.

    ``commands`` maps a step index to (torque, frame_id, stamp): received at that step.
    ``log_time``: the recording's time base, ``sim`` (the node's default) or ``wall``.
    """
    scene_path = SCENES / f"{scene_name}.yaml"
    scene = load_scene(scene_path)
    sim = Simulator(scene, method=method)
    torque_topic = "/rigid_rot_sim/torque"
    with RunRecorder(
        path,
        scene_text=scene_path.read_text(),
        scene_file=str(scene_path),
        parameters={"integrator": scene.integrator.method},
        events_topic="/rigid_rot_sim/sim_events",
        integrator={"method": sim.stepper.method, "dt": sim.clock.dt, "options": sim.stepper.options},
        sim_seconds=(lambda: sim.clock.t) if log_time == "sim" else None,
    ) as run:
        run.add_topic("/rigid_rot_sim/state", RigidBodyState, role="state")
        run.add_topic(torque_topic, WrenchStamped, role="torque")
        # as the node does: the recording observes the simulator, so every command is recorded as an event
        recording = NodeRecording(run, sim, None)
        sim.add_observer(recording)
        states = []
        for k in range(0, steps, publish_every):
            if k in commands:
                torque, frame_id, stamp = commands[k]
                msg = WrenchStamped()
                msg.header.frame_id = frame_id
                msg.header.stamp = conversions.seconds_to_time(stamp)
                msg.wrench.torque = conversions.array_to_vector3(torque)
                received_ns = run.log_time_ns()
                try:
                    sim.receive_torque("~/torque", torque, frame_id, stamp)
                except CommandRejected:
                    pass
                recording.received(torque_topic, msg, received_ns)
            sim.advance_to(k)
            snapshot = sim.snapshot()
            states.append(snapshot)
            run.record("/rigid_rot_sim/state", conversions.snapshot_to_state(snapshot, "odom", "base_link"))
            run.record_tf(*divmod(round(snapshot.t * 1e9), 1_000_000_000), snapshot.orientation, "odom", "base_link")
    return sim, states


COMMANDS = {
    0: ((0.0, 0.0, 0.002), "base_link", 0.0),
    100: ((0.001, -0.002, 0.0), "odom", 0.1234567),  # future stamp: effective later
    300: ((0.0, 0.003, 0.0), "base_link", 0.0),
    450: ((0.0, 0.0, 0.0), "base_link", 0.0),
}


def test_same_integrator_reproduces_every_state_bit_for_bit(tmp_path):
    path = tmp_path / "run.mcap"
    sim, states = record_like_the_node(path, "torque_driven", 1200, 10, COMMANDS)
    assert np.linalg.norm(states[-1].angular_velocity_body) > 0.01  # the commands did act
    report = resimulate(path)
    assert report.identical, report.format()
    assert report.states == len(states) and report.events == len(COMMANDS)
    assert report.max_attitude_error == 0.0 and report.max_omega_error == 0.0
    assert "BIT-EXACT" in report.verdict


def test_resim_checks_the_run_digest(tmp_path):
    path = tmp_path / "run.mcap"
    _, states = record_like_the_node(path, "torque_driven", 600, 10, COMMANDS)
    report = resimulate(path)
    assert report.digest == report.recorded_digest == states[-1].digest != 0
    assert report.digest_verdict == "equal" and "equal" in report.format()
    other = resimulate(path, method="lie_rk4")  # another integrator: other states, another digest
    assert other.digest != other.recorded_digest and other.digest_verdict == "different"
    assert "different" in other.format()


def test_another_integrator_reports_a_small_nonzero_difference(tmp_path):
    path = tmp_path / "run.mcap"
    _, states = record_like_the_node(path, "torque_driven", 1200, 10, COMMANDS)
    other = "lie_rk4"
    report = resimulate(path, method=other)
    assert not report.identical
    assert report.method == other
    assert 0.0 < report.max_attitude_error < 0.1
    assert 0.0 < report.max_omega_error
    assert "DIFFERS" in report.verdict and report.first_difference_t is not None


def test_free_tumble_resim_is_exact(tmp_path):
    path = tmp_path / "free.mcap"
    record_like_the_node(path, "free_tumble", 300, 5, {}, method="exact")
    report = resimulate(path)
    assert report.identical and report.events == 0 and report.states == 60


def test_attitude_angle_is_accurate_for_tiny_and_large_rotations():
    from scipy.spatial.transform import Rotation

    q = Rotation.from_rotvec([0.3, -0.2, 0.9]).as_quat()
    for angle in (1e-12, 1e-6, 0.5, 3.0):
        dq = Rotation.from_rotvec(np.array([1.0, 2.0, -2.0]) / 3.0 * angle)
        q2 = (Rotation.from_quat(q) * dq).as_quat()
        assert attitude_angle(q, q2) == pytest.approx(angle, rel=1e-6)
        assert attitude_angle(q, -q2) == pytest.approx(angle, rel=1e-6)  # sign-blind


def test_report_says_when_the_numerical_core_changed_since_the_recording(tmp_path, monkeypatch):
    path = tmp_path / "run.mcap"
    record_like_the_node(path, "torque_driven", 200, 10, COMMANDS)
    assert resimulate(path).core_changed is False
    monkeypatch.setattr("rigid_rot_sim.recording.resim.core_fingerprint", lambda: "another core")
    report = resimulate(path)
    assert report.core_changed is True
    assert "changed since the recording" in report.format()


def record_wheels(path: Path, tamper_angle_at: int | None = None):
    """The wheel_slew scene run as the node runs it, ~/wheels (angles, speeds, torques) recorded beside ~/state,
    with wheel commands from a JointState door's topic; ``tamper_angle_at``: a state index whose recorded wheel
    angle is changed in its last bit."""
    from sensor_msgs.msg import JointState

    scene_path = SCENES / "wheel_slew.yaml"
    scene = load_scene(scene_path)
    sim = Simulator(scene, method="gyrostat_rk4")
    with RunRecorder(
        path,
        scene_text=scene_path.read_text(),
        scene_file=str(scene_path),
        parameters={"integrator": "gyrostat_rk4"},
        events_topic="/rigid_rot_sim/sim_events",
        integrator={"method": sim.stepper.method, "dt": sim.clock.dt, "options": sim.stepper.options},
        sim_seconds=lambda: sim.clock.t,
    ) as run:
        run.add_topic("/rigid_rot_sim/state", RigidBodyState, role="state")
        run.add_topic("/rigid_rot_sim/wheels", JointState, role="wheels")
        sim.add_observer(NodeRecording(run, sim, None))
        for i, k in enumerate(range(0, 3000, 50)):
            if k == 1200:  # a command of the door, as its source names it: replayed by resim from the event
                sim.submit_wheel_torques("/rw_joint_commands", [0.05, -0.02, 0.0])
            sim.advance_to(k)
            snapshot = sim.snapshot()
            run.record("/rigid_rot_sim/state", conversions.snapshot_to_state(snapshot, "odom", "base_link"))
            wheels = conversions.snapshot_to_joint_state(snapshot, "base_link")
            if i == tamper_angle_at:
                wheels.position[2] = float(np.nextafter(wheels.position[2], np.inf))
            run.record("/rigid_rot_sim/wheels", wheels)
    return sim.snapshot()


def test_a_wheel_run_reproduces_the_wheel_angles_bit_for_bit(tmp_path):
    last = record_wheels(tmp_path / "run.mcap")
    assert abs(last.wheel_angles[2]) > 2 * np.pi and last.wheel_angles[0] != 0.0  # turned, and commanded
    report = resimulate(tmp_path / "run.mcap")
    assert report.identical and report.wheel_states == 60 and report.wheel_mismatches == 0, report.format()
    assert report.digest_verdict == "equal"
    assert "60 wheel states" in report.verdict
    record_wheels(tmp_path / "tampered.mcap", tamper_angle_at=40)
    tampered = resimulate(tmp_path / "tampered.mcap")
    assert not tampered.identical and tampered.wheel_mismatches == 1
    assert tampered.max_attitude_error == 0.0 and tampered.digest_verdict == "equal"  # the body agrees
    assert "1 of 60 wheel states differ" in tampered.verdict

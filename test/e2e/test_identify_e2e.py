"""End to end: record the excitation scene with its gyro, identify the body from the recording, run the
body the identification wrote, and its replay of the first run is at the gyro's noise floor.

The node records its own run (``rigid-rot run --record``); ``rigid-rot identify`` reads the file as a
user's bag, without options; the second run is a fresh node on the scene with the written body.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import yaml

from rigid_rot_sim.recording.reader import BagReader

REPO = Path(__file__).resolve().parents[2]
CLI = [str(Path(sys.executable).with_name("rigid-rot"))]
DURATION = "15"
#: The scene's gyro: angle random walk 1e-4 rad/sqrt(s) at 100 Hz is 1e-3 rad/s per reading.
NOISE = 1e-3


def _run(scene: Path, record: Path, env: dict[str, str]) -> None:
    done = subprocess.run(
        CLI + ["run", str(scene), "--duration", DURATION, "--record", str(record)],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stdout + done.stderr


def _series(path: Path, topic: str, field: str) -> tuple[np.ndarray, np.ndarray]:
    times, values = [], []
    for _, msg in BagReader(path).decoded([topic]):
        times.append(msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec)
        v = getattr(msg, field)
        values.append([v.x, v.y, v.z])
    return np.array(times), np.array(values)


def test_identified_body_replays_the_recording_at_the_noise_floor(tmp_path, ros_env):
    scene = REPO / "config" / "scenes" / "excitation.yaml"
    first = tmp_path / "first.mcap"
    _run(scene, first, ros_env)

    body_file = tmp_path / "body.yaml"
    done = subprocess.run(
        CLI + ["identify", str(first), "--estimate", "inertia,gyro_bias", "--json", "--out", str(body_file)],
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert result["identifiable"] == "full"
    truth = np.array(yaml.safe_load(scene.read_text())["body"]["inertia_tensor"])
    error = np.abs(np.array(result["inertia"]) - truth)
    assert np.all(error <= 4.0 * np.array(result["inertia_sigma"])), (error, result["inertia_sigma"])
    assert result["residual_rms"] < 1.2 * NOISE

    spec = yaml.safe_load(scene.read_text())
    spec["body"] = yaml.safe_load(body_file.read_text())["body"]
    identified_scene = tmp_path / "identified.yaml"
    identified_scene.write_text(yaml.safe_dump(spec, sort_keys=False))
    second = tmp_path / "second.mcap"
    _run(identified_scene, second, ros_env)

    # the first run's gyro readings against the identified body's true rate (and its gyro bias) at the same stamps
    t_imu, readings = _series(first, "/rigid_rot_sim/imu", "angular_velocity")
    t_state, rates = _series(second, "/rigid_rot_sim/state", "angular_velocity_body")
    common, i, j = np.intersect1d(t_imu, t_state, return_indices=True)
    assert common.size > 1000
    residual = readings[i] - np.array(result["gyro_bias"]) - rates[j]
    rms = float(np.sqrt(np.mean(residual**2)))
    assert rms < 1.15 * NOISE, rms
    # and identify's own validation replay (our integrator, from the fitted initial rate) says the same
    assert result["validation"]["identified_rms"]["omega"] < 1.15 * NOISE

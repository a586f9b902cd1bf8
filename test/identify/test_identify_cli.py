"""``rigid-rot identify`` as a user runs it: JSON on stdout, the body YAML, plots; bad input: one line, exit 2."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from identify_truth import INERTIA, excitation, gyro, simulate, write_bag  # beside this file

CLI = [str(Path(sys.executable).with_name("rigid-rot")), "identify"]


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    times, values = excitation(12.0, 1.0, 0.01, seed=4)
    truth = simulate(INERTIA, np.array([0.3, -0.2, 0.4]), 12.0, 100.0, times, values, frame="world")
    return write_bag(
        tmp_path_factory.mktemp("bag") / "bag", truth, gyro(truth, 1e-3, np.zeros(3), 6), with_orientation=True
    )


def identify(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(CLI + list(args), capture_output=True, text=True, timeout=300)


def test_json_body_and_plots(bag, tmp_path):
    body = tmp_path / "body.yaml"
    done = identify(str(bag), "--imu", "/robot/imu", "--torque", "/robot/torque", "--json",
                    "--nominal", "torque_driven", "--out", str(body), "--plot", str(tmp_path / "plots"))  # fmt: skip
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    for key in ("inertia", "inertia_sigma", "principal_moments", "principal_moments_sigma", "identifiable",
                "torque_bias", "gyro_bias", "residual_rms", "validation"):  # fmt: skip
        assert key in result
    assert result["identifiable"] == "full" and result["torque_bias"] is None and result["gyro_bias"] is None
    assert np.all(np.abs(np.array(result["inertia"]) - INERTIA) < 4 * np.array(result["inertia_sigma"]))
    assert result["principal_moments"] == sorted(result["principal_moments"])
    validation = result["validation"]
    assert validation["identified_rms"]["omega"] < 0.1 * validation["nominal_rms"]["omega"]
    assert validation["identified_rms"]["attitude"] < validation["nominal_rms"]["attitude"]
    assert "inertia_tensor" in body.read_text()
    assert sorted(p.name for p in (tmp_path / "plots").iterdir()) == ["replay_rate.png", "replay_residuals.png"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["--imu", "/nope", "--torque", "/robot/torque"],
            "no such topic .* it has /robot/imu \\(sensor_msgs/msg/Imu\\)",
        ),
        (["--imu", "/robot/torque"], "type geometry_msgs/msg/WrenchStamped, expected sensor_msgs/msg/Imu"),
        (["--imu", "/robot/imu", "--torque", "/robot/torque", "--start", "3", "--end", "3.1"], "at least 20"),
        (["--imu", "/robot/imu", "--torque", "/robot/torque", "--estimate", "mass"], "unknown mass"),
        ([], "not a rigid_rot_sim recording"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(bag, args, message):
    import re

    done = identify(str(bag), *args)
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and re.search(message, lines[0]), lines


def test_unknown_torque_frame_is_refused_and_can_be_named(tmp_path):
    times, values = excitation(3.0, 1.0, 0.01, seed=4)
    truth = simulate(INERTIA, np.array([0.3, -0.2, 0.4]), 3.0, 100.0, times, values)
    bag = write_bag(tmp_path / "bag", truth, truth.omega, command_frame="gimbal")
    done = identify(str(bag), "--imu", "/robot/imu", "--torque", "/robot/torque")
    assert done.returncode == 2 and "unknown frame 'gimbal'" in done.stderr and len(done.stderr.splitlines()) == 1
    done = identify(str(bag), "--imu", "/robot/imu", "--torque", "/robot/torque", "--body-frame", "gimbal", "--json")
    assert done.returncode == 0, done.stderr
    assert np.allclose(json.loads(done.stdout)["inertia"], INERTIA, rtol=1e-6, atol=1e-10)

"""End to end: the node in its own process answers ~/compute_inertia over DDS."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rigid_rot_sim.core.inertia import mass_properties, principal_orientation

SERVICE = "/rigid_rot_sim/compute_inertia"
REPO = Path(__file__).resolve().parents[2]
SAMPLE_BODY = REPO / "config" / "bodies" / "sample_body.yaml"


@pytest.fixture(scope="module")
def inertia_node(launch_node_module):
    return launch_node_module(name="rigid_rot_sim")


@pytest.fixture(scope="module")
def client_node(ros_node_module):
    return ros_node_module


@pytest.fixture(scope="module")
def inertia_client(client_node, inertia_node, wait_for_service):
    from rigid_rot_msgs.srv import ComputeInertia

    client = client_node.create_client(ComputeInertia, SERVICE)
    wait_for_service(client, process=inertia_node)
    return client


def make_request(masses, positions, origin=(0.0, 0.0, 0.0), frame_id="base_link"):
    from geometry_msgs.msg import Point

    from rigid_rot_msgs.srv import ComputeInertia

    request = ComputeInertia.Request()
    request.masses = [float(m) for m in masses]
    request.positions = [Point(x=float(x), y=float(y), z=float(z)) for x, y, z in positions]
    request.origin = Point(x=float(origin[0]), y=float(origin[1]), z=float(origin[2]))
    request.frame_id = frame_id
    return request


def assert_response_matches(response, expected):
    assert response.success, response.message
    assert response.total_mass == pytest.approx(expected.total_mass, rel=1e-15)
    com = response.center_of_mass
    np.testing.assert_allclose([com.x, com.y, com.z], expected.center_of_mass, rtol=1e-15, atol=1e-300)
    np.testing.assert_allclose(np.reshape(response.inertia_origin, (3, 3)), expected.inertia_origin, rtol=1e-15)
    np.testing.assert_allclose(np.reshape(response.inertia_com, (3, 3)), expected.inertia_com, rtol=1e-15)
    np.testing.assert_allclose(response.principal_moments, expected.principal_moments, rtol=1e-15)
    axes = np.reshape(response.principal_axes, (3, 3))  # row-major: columns are the axes
    np.testing.assert_allclose(axes, expected.principal_axes, rtol=1e-15)
    q = response.principal_orientation
    np.testing.assert_allclose([q.x, q.y, q.z, q.w], principal_orientation(expected.principal_axes), rtol=1e-15)
    assert response.symmetry == expected.symmetry
    inertia = response.inertia  # geometry_msgs/Inertia: about the centre of mass
    assert inertia.m == pytest.approx(expected.total_mass, rel=1e-15)
    np.testing.assert_allclose([inertia.com.x, inertia.com.y, inertia.com.z], expected.center_of_mass)
    tensor = expected.inertia_com
    np.testing.assert_allclose(
        [inertia.ixx, inertia.ixy, inertia.ixz, inertia.iyy, inertia.iyz, inertia.izz],
        [tensor[0, 0], tensor[0, 1], tensor[0, 2], tensor[1, 1], tensor[1, 2], tensor[2, 2]],
    )


def test_bad_request_then_good_request(client_node, inertia_client, inertia_node, call_service):
    bad = call_service(client_node, inertia_client, make_request([1.0, 2.0], [[0.0, 0.0, 0.0]]))
    assert not bad.success
    assert "positions has 1 points but masses has 2" in bad.message

    masses = [12.0, 1.5, 1.5, 0.4, 3.0]
    positions = [[0.0, 0.0, 0.0], [0.0, 0.9, 0.05], [0.0, -0.9, 0.05], [0.0, 0.0, 0.75], [0.12, 0.08, -0.1]]
    origin = (0.1, -0.2, 0.3)
    good = call_service(client_node, inertia_client, make_request(masses, positions, origin))
    assert_response_matches(good, mass_properties(masses, positions, origin))
    assert good.symmetry == "asymmetric"
    inertia_node.check_alive()


@pytest.mark.parametrize(
    "masses, positions, message",
    [
        ([float("nan")], [[0.0, 0.0, 0.0]], "masses[0] must be finite"),
        ([1.0, -1.0], [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], "masses[1] must be > 0"),
        ([1.0], [[0.0, float("inf"), 0.0]], "positions[0] must be finite"),
        ([], [], "at least one mass"),
    ],
)
def test_invalid_requests_are_rejected_and_the_node_keeps_serving(
    client_node, inertia_client, inertia_node, call_service, masses, positions, message
):
    response = call_service(client_node, inertia_client, make_request(masses, positions))
    assert not response.success
    assert message in response.message
    ok = call_service(client_node, inertia_client, make_request([1.0], [[0.0, 0.0, 0.0]]))
    assert ok.success and ok.symmetry == "point"
    inertia_node.check_alive()


def test_degenerate_dumbbell_over_dds(client_node, inertia_client, call_service):
    masses, positions = [2.0, 3.0], [[0.0, 0.0, -0.5], [0.0, 0.0, 1.0]]
    response = call_service(client_node, inertia_client, make_request(masses, positions))
    assert_response_matches(response, mass_properties(masses, positions))
    assert response.symmetry == "linear"
    assert response.principal_moments[0] == 0.0
    reduced = 2.0 * 3.0 / 5.0
    assert response.principal_moments[2] == pytest.approx(reduced * 1.5**2, rel=1e-14)


def test_cli_asks_the_service_and_agrees_with_the_library(inertia_node, ros_env):
    rigid_rot = Path(sys.executable).parent / "rigid-rot"
    result = subprocess.run(
        [str(rigid_rot), "inertia", str(SAMPLE_BODY), "--service", SERVICE, "--compare", "--timeout", "30"],
        capture_output=True,
        text=True,
        timeout=120,
        env=ros_env,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert f"computed by {SERVICE}" in result.stdout
    assert "service answer matches the library" in result.stdout


def test_cli_takes_ros_args_for_its_client_node(inertia_node, ros_env):
    """A relative service name resolved in the namespace given with --ros-args."""
    rigid_rot = Path(sys.executable).parent / "rigid-rot"
    namespace, relative = SERVICE.rsplit("/", 1)
    result = subprocess.run(
        [
            str(rigid_rot),
            "inertia",
            str(SAMPLE_BODY),
            "--service",
            relative,
            "--timeout",
            "30",
            "--ros-args",
            "-r",
            f"__ns:={namespace}",
        ],
        capture_output=True,
        text=True,
        timeout=120,
        env=ros_env,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "total mass" in result.stdout


def test_node_stops_cleanly_on_sigint(launch_node, ros_node, wait_for_service):
    from rigid_rot_msgs.srv import ComputeInertia

    # its own namespace, so the wait below cannot be answered by the module's node
    node = launch_node("--ros-args", "-r", "__ns:=/sigint_test", name="sigint")
    wait_for_service(ros_node.create_client(ComputeInertia, "/sigint_test" + SERVICE), process=node)
    assert node.stop() == 0, node.log()
    assert "Traceback" not in node.log()

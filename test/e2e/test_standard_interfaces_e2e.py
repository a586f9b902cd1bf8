"""End to end over DDS: the standard interfaces a ROS tool chain expects of the node.

* the simulation_interfaces services (the ROS 2 simulator standard), each called with a
  request it must refuse (with the Result code that says why) and then with a good one;
* ``~/imu`` (sensor_msgs/Imu) and ``~/odom`` (nav_msgs/Odometry), built because the scene
  asks for them, carrying the same attitude and rate as ``~/state`` at the same stamp;
* frame names from the ``world_frame`` / ``body_frame`` parameters on every output.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_node_e2e import NODE, SCENES, stamp  # noqa: E402 (collector: a conftest fixture)

WORLD, BODY = "map_test", "satellite"


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory) -> Path:
    """free_tumble with ~/imu and ~/odom asked for (they are off by default)."""
    scene = yaml.safe_load((SCENES / "free_tumble.yaml").read_text())
    scene["outputs"].update({"imu": 100, "odom": 100, "state": 100})
    path = tmp_path_factory.mktemp("scene") / "imu_scene.yaml"
    path.write_text(yaml.safe_dump(scene, sort_keys=False))
    return path


@pytest.fixture(scope="module")
def sim_node(launch_node_module, scene_file):
    return launch_node_module(
        "--ros-args",
        "-p",
        f"scene:={scene_file}",
        "-p",
        "real_time_factor:=1.0",
        "-p",
        f"world_frame:={WORLD}",
        "-p",
        f"body_frame:={BODY}",
        name="standard",
    )


def test_simulation_interfaces_services_refuse_bad_requests_and_serve_good_ones(sim_node, collector):
    from simulation_interfaces.msg import Result, SimulationState, SimulatorFeatures
    from simulation_interfaces.srv import (
        GetSimulationState,
        GetSimulatorFeatures,
        ResetSimulation,
        SetSimulationState,
        StepSimulation,
    )

    from rigid_rot_msgs.srv import Step

    def call(srv_type, name, request):
        return collector.call(srv_type, name, request, process=sim_node)

    def run_state() -> int:
        response = call(GetSimulationState, "get_simulation_state", GetSimulationState.Request())
        assert response.result.result == Result.RESULT_OK, response.result.error_message
        return response.state.state

    def set_state(state: int):
        return call(
            SetSimulationState, "set_simulation_state", SetSimulationState.Request(state=SimulationState(state=state))
        ).result

    def now() -> float:
        """Sim time (s) after one more step of the node's own ~/step (which returns the state)."""
        response = call(Step, "step", Step.Request(steps=1))
        assert response.success, response.message
        return stamp(response.state)

    features = call(GetSimulatorFeatures, "get_simulator_features", GetSimulatorFeatures.Request()).features
    assert {
        SimulatorFeatures.STEP_SIMULATION_MULTIPLE,
        SimulatorFeatures.SIMULATION_RESET,
        SimulatorFeatures.SIMULATION_STATE_PAUSE,
    } <= set(features.features)
    assert SimulatorFeatures.SPAWNING not in features.features and "ResetSimulation" in features.custom_info
    assert "at most 10000 steps per request" in features.custom_info  # StepSimulation's limit, said (issue 40)
    assert run_state() == SimulationState.STATE_PLAYING

    # set state: bad (already there, QUITTING, unknown) then good
    assert set_state(SimulationState.STATE_PLAYING).result == SetSimulationState.Response.ALREADY_IN_TARGET_STATE
    assert set_state(SimulationState.STATE_QUITTING).result == Result.RESULT_FEATURE_UNSUPPORTED
    unknown = set_state(77)
    assert unknown.result == Result.RESULT_OPERATION_FAILED and "unknown simulation state 77" in unknown.error_message
    assert set_state(SimulationState.STATE_PAUSED).result == Result.RESULT_OK
    assert run_state() == SimulationState.STATE_PAUSED

    # step: bad (while playing, zero steps) then good
    assert set_state(SimulationState.STATE_PLAYING).result == Result.RESULT_OK
    playing = call(StepSimulation, "step_simulation", StepSimulation.Request(steps=5)).result
    # StepSimulation.srv: "Calling with simulation not paused will return RESULT_OPERATION_FAILED"
    assert playing.result == Result.RESULT_OPERATION_FAILED and "paused" in playing.error_message
    assert set_state(SimulationState.STATE_PAUSED).result == Result.RESULT_OK
    zero = call(StepSimulation, "step_simulation", StepSimulation.Request(steps=0)).result
    assert zero.result == Result.RESULT_OPERATION_FAILED and "steps must be >= 1" in zero.error_message
    t0 = now()
    assert call(StepSimulation, "step_simulation", StepSimulation.Request(steps=25)).result.result == Result.RESULT_OK
    assert now() == pytest.approx(t0 + 26 * 0.01, abs=1e-9)  # dt 0.01 s; still paused between the calls

    # reset: bad (time without state) then good (state only at the current time, then everything)
    time_only = call(
        ResetSimulation, "reset_simulation", ResetSimulation.Request(scope=ResetSimulation.Request.SCOPE_TIME)
    ).result
    assert time_only.result == Result.RESULT_FEATURE_UNSUPPORTED and "without the state" in time_only.error_message
    t1 = now()
    state_only = ResetSimulation.Request(scope=ResetSimulation.Request.SCOPE_STATE)
    assert call(ResetSimulation, "reset_simulation", state_only).result.result == Result.RESULT_OK
    stepped = call(Step, "step", Step.Request(steps=1)).state
    assert stamp(stepped) == pytest.approx(t1 + 0.01, abs=1e-9)  # time kept
    everything = ResetSimulation.Request(scope=ResetSimulation.Request.SCOPE_DEFAULT)
    assert call(ResetSimulation, "reset_simulation", everything).result.result == Result.RESULT_OK
    fresh = call(Step, "step", Step.Request(steps=1)).state
    assert stamp(fresh) == pytest.approx(0.01, abs=1e-12)  # back to t = 0, then one step
    # torque-free motion is autonomous: one step from the initial state gives the same ω at any time
    for axis in "xyz":
        assert getattr(stepped.angular_velocity_body, axis) == pytest.approx(
            getattr(fresh.angular_velocity_body, axis), rel=1e-9
        )

    # stop = pause + reset; playing again runs
    assert set_state(SimulationState.STATE_STOPPED).result == Result.RESULT_OK
    assert run_state() == SimulationState.STATE_STOPPED
    assert set_state(SimulationState.STATE_PLAYING).result == Result.RESULT_OK
    assert run_state() == SimulationState.STATE_PLAYING
    sim_node.check_alive()


def test_imu_and_odom_carry_the_state_of_the_same_stamp_in_the_parameter_frames(sim_node, collector):
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import Imu

    from rigid_rot_msgs.msg import RigidBodyState
    from rigid_rot_sim.ros.qos import STATE_QOS

    states = collector.subscribe(RigidBodyState, f"{NODE}/state", STATE_QOS)
    imus = collector.subscribe(Imu, f"{NODE}/imu", STATE_QOS)
    odoms = collector.subscribe(Odometry, f"{NODE}/odom", STATE_QOS)

    def common_stamps():
        return ({stamp(m) for m in states} & {stamp(m) for m in imus} & {stamp(m) for m in odoms}) - {0.0}

    collector.spin_until(
        lambda: len(common_stamps()) >= 3, 30.0, sim_node, "~/state, ~/imu and ~/odom at common stamps"
    )
    by_stamp = {stamp(m): m for m in states}
    imu_by_stamp = {stamp(m): m for m in imus}
    odom_by_stamp = {stamp(m): m for m in odoms}
    for t in sorted(common_stamps()):
        state, imu, odom = by_stamp[t], imu_by_stamp[t], odom_by_stamp[t]
        q = (state.orientation.x, state.orientation.y, state.orientation.z, state.orientation.w)
        w = (state.angular_velocity_body.x, state.angular_velocity_body.y, state.angular_velocity_body.z)
        assert (imu.orientation.x, imu.orientation.y, imu.orientation.z, imu.orientation.w) == q
        assert (imu.angular_velocity.x, imu.angular_velocity.y, imu.angular_velocity.z) == w
        pose = odom.pose.pose
        assert (pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w) == q
        assert (pose.position.x, pose.position.y, pose.position.z) == (0.0, 0.0, 0.0)
        angular = odom.twist.twist.angular
        assert (angular.x, angular.y, angular.z) == w
        # frames from the parameters: the IMU is the body frame; odometry world -> body
        assert imu.header.frame_id == BODY and (state.header.frame_id, state.child_frame_id) == (WORLD, BODY)
        assert (odom.header.frame_id, odom.child_frame_id) == (WORLD, BODY)
        # covariances as documented: exact values (ground_truth_variance on the diagonals), no acceleration
        assert imu.linear_acceleration_covariance[0] == -1.0
        assert list(imu.orientation_covariance) == [1e-12, 0, 0, 0, 1e-12, 0, 0, 0, 1e-12]
        assert list(imu.angular_velocity_covariance) == list(imu.orientation_covariance)
        assert [odom.pose.covariance[7 * i] for i in range(6)] == [1e-12] * 6
    assert any(abs(w) > 0.1 for w in (by_stamp[t].angular_velocity_body.z for t in common_stamps()))  # it tumbles
    sim_node.check_alive()

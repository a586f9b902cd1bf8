"""Physics through the environments' own interface: the exact torque-free flow, the wheels' momentum."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core.exact import torque_free_flow
from rigid_rot_sim.core.integrators.gyrostat import GyrostatRK4
from rigid_rot_sim.core.torque import ConstantTorque
from rigid_rot_sim.core.wheels import total_momentum_body
from rigid_rot_sim.envs.attitude import AttitudeControlEnv, WheelAttitudeControlEnv
from rigid_rot_sim.envs.vector import WheelAttitudeControlVectorEnv

#: What RK4 with dt = 0.01 s keeps over a 30 s episode at rates up to 0.87 rad/s (its global error ~ (omega dt)^4
#: omega t): measured 3.6e-13 rad and 5.1e-14 rad/s at worst over these seeds (|omega0| up to 0.53 rad/s), 1.8e-12
#: and 1.0e-14 with other draws; the bounds leave ~50x.
ANGLE_TOLERANCE = 1e-10  # rad
RATE_TOLERANCE = 1e-12  # rad/s


def test_zero_action_on_a_torque_free_body_follows_the_exact_flow():
    env = AttitudeControlEnv(max_initial_rate=0.5, hold_periods=1_000)
    for seed in (0, 1, 2):
        obs, info = env.reset(seed=seed)
        q0, omega0 = obs[:4].copy(), obs[4:7].copy()
        worst_angle = worst_rate = 0.0
        for k in range(1, env.task.max_episode_steps + 1):
            obs, reward, terminated, truncated, _ = env.step(np.zeros(3, dtype=np.float32))
            q_exact, omega_exact = torque_free_flow(info["principal_moments"], q0, omega0, k * env.task.control_period)
            delta = Rotation.from_quat(q_exact).inv() * Rotation.from_quat(obs[:4])
            worst_angle = max(worst_angle, float(delta.magnitude()))
            worst_rate = max(worst_rate, float(np.max(np.abs(obs[4:7] - omega_exact))))
        assert truncated and not terminated
        assert worst_angle < ANGLE_TOLERANCE, worst_angle
        assert worst_rate < RATE_TOLERANCE, worst_rate
        assert worst_angle > 0.0  # an integrator, not the flow itself


def _world_momentum(env, obs, moments):
    wheels = env.bodies.wheel_model
    h_body = total_momentum_body(moments, wheels, obs[4:7], obs[10:13])
    return Rotation.from_quat(obs[:4]).apply(h_body)


def test_the_wheel_env_conserves_total_angular_momentum_without_friction():
    """Zero motor torque, then any motor torque: internal torques only, so the world-frame momentum holds."""
    env = WheelAttitudeControlEnv(max_initial_rate=0.5, hold_periods=1_000)
    actions = {
        "zero": lambda rng: np.zeros(3, dtype=np.float32),
        "random": lambda rng: rng.uniform(-1, 1, 3).astype(np.float32),
    }
    for name, draw in actions.items():
        rng = np.random.default_rng(9)
        obs, info = env.reset(seed=4)
        h0 = _world_momentum(env, obs, info["principal_moments"])
        drift = 0.0
        for _ in range(env.task.max_episode_steps):
            obs, *_ = env.step(draw(rng))
            drift = max(drift, float(np.linalg.norm(_world_momentum(env, obs, info["principal_moments"]) - h0)))
        # |H0| = 0.43 N*m*s; measured drift 6.8e-14 (zero torque) and 7.3e-13 (random torques): RK4's error
        assert drift < 1e-11 * float(np.linalg.norm(h0)), (name, drift)
        if name == "random":
            assert np.max(np.abs(obs[10:13])) > 1.0  # the wheels did take up momentum


def test_a_wheel_slot_has_the_bits_of_the_engines_single_body_gyrostat_integrator():
    envs = WheelAttitudeControlVectorEnv(num_envs=3, hold_periods=1_000)
    obs, info = envs.reset(seed=[7, 8, 9])
    task = envs.task
    integrators = [
        GyrostatRK4(
            info["principal_moments"][i],
            task.dt,
            ConstantTorque(np.zeros(3)),
            wheels=envs.bodies.wheel_model,
            q0=obs[i, :4],
            omega0=obs[i, 4:7],
            wheel_speeds0=obs[i, 10:13],
        )
        for i in range(3)
    ]
    # set_state normalises q again (which may move its last bit): start the slots from the integrators' q
    envs.bodies.q[:] = [integrator.q for integrator in integrators]
    actions = np.random.default_rng(2).uniform(-1, 1, (20, 3, 3)).astype(np.float32)
    for a in actions:
        obs, *_ = envs.step(a)
        for i, integrator in enumerate(integrators):
            integrator.set_wheel_commands(a[i].astype(float) * task.max_torque)
            integrator.advance(task.substeps)
            state = np.concatenate((integrator.q, integrator.omega, integrator.wheel_speeds))
            assert state.tobytes() == np.concatenate((obs[i, :7], obs[i, 10:13])).tobytes()

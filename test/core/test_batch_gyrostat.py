"""advance_gyrostats: every body has the bits of the engine's single-body GyrostatRK4."""

from __future__ import annotations

import numpy as np
import pytest

from rigid_rot_sim.core.batch_gyrostat import advance_gyrostats, hub_inverses
from rigid_rot_sim.core.integrators.base import NonFiniteStateError
from rigid_rot_sim.core.integrators.gyrostat import GyrostatRK4
from rigid_rot_sim.core.torque import ConstantTorque
from rigid_rot_sim.core.wheels import wheel_model


def _wheels(friction=False):
    axes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]]
    drag = {"coulomb": [2e-3] * 4, "viscous": [1e-4] * 4, "stiction_speed": [0.5] * 4} if friction else {}
    return wheel_model(np.diag([2.0, 2.5, 3.0]), list("abcd"), axes, [0.01] * 4, [0.1] * 4, [50.0] * 4, **drag)


@pytest.mark.parametrize("layout", ["soa", "per_body"])
@pytest.mark.parametrize(
    ("n", "n_steps"), [(5, 1), (5, 7), (5, 5_000), (300, 70)]
)  # 5 x 5000 and 300 x 70 steps: the parallel loops; 300 bodies: chunks of the SIMD layout and a partial one
@pytest.mark.parametrize("friction", [False, True])
def test_each_body_matches_the_single_body_integrator_bit_for_bit(n, n_steps, layout, friction):
    rng = np.random.default_rng(0)
    wheels = _wheels(friction)
    moments = np.array([2.0, 2.5, 3.0]) * (1.0 + 0.05 * rng.uniform(-1, 1, (n, 3)))
    q0 = rng.normal(size=(n, 4))
    omega = rng.normal(size=(n, 3))
    speeds = rng.uniform(-49.0, 49.0, (n, 4))  # some near the speed limit, where the motor torque fades
    speeds[::3] = rng.uniform(-0.6, 0.6, (len(speeds[::3]), 4))  # some in the stiction band
    commands = rng.uniform(-0.1, 0.1, (n, 4))
    torque = rng.normal(size=(n, 3)) * 1e-2
    singles = [
        GyrostatRK4(
            moments[b],
            0.01,
            ConstantTorque(torque[b]),
            wheels=wheels,
            q0=q0[b],
            omega0=omega[b],
            wheel_speeds0=speeds[b],
        )
        for b in range(n)
    ]
    q = np.array([single.q for single in singles])  # normalised by set_state: the batch takes q as it is
    q_b, omega_b, speeds_b = advance_gyrostats(
        moments, wheels, q, omega, speeds, commands, 0.01, n_steps, torque_body=torque, layout=layout
    )
    for b, single in enumerate(singles):
        single.set_wheel_commands(commands[b])
        single.advance(n_steps)
        assert single.q.tobytes() == q_b[b].tobytes()
        assert single.omega.tobytes() == omega_b[b].tobytes()
        assert single.wheel_speeds.tobytes() == speeds_b[b].tobytes()
    # the precomputed hub inverses give the same bits
    again = advance_gyrostats(
        moments,
        wheels,
        q,
        omega,
        speeds,
        commands,
        0.01,
        n_steps,
        torque_body=torque,
        hub_inverse=hub_inverses(moments, wheels),
        layout=layout,
    )
    assert again[0].tobytes() == q_b.tobytes()


def test_bad_input_and_a_non_finite_state_are_reported():
    wheels = _wheels()
    ok = (np.array([[2.0, 2.5, 3.0]]), wheels, [[0.0, 0.0, 0.0, 1.0]], [[0.0, 0.0, 0.0]], [[0.0] * 4], [[0.0] * 4])
    with pytest.raises(ValueError, match="dt"):
        advance_gyrostats(*ok, 0.0, 1)
    with pytest.raises(ValueError, match="n_steps"):
        advance_gyrostats(*ok, 0.01, -1)
    with pytest.raises(ValueError, match="wheel_commands"):
        advance_gyrostats(*ok[:5], [[np.nan] * 4], 0.01, 1)
    with pytest.raises(NonFiniteStateError, match="body 0"):
        advance_gyrostats(ok[0], wheels, ok[2], [[1e200, 1e200, 1e200]], ok[4], ok[5], 0.01, 10)

"""run.digest: the definition, byte for byte, and that the simulator's digest is every step's."""

import struct

import numpy as np

from rigid_rot_sim.run.digest import DIGEST_SEED, FNV_PRIME, fold_steps, format_digest
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import parse_scene_text


def _reference(steps):
    """The module docstring's definition, written out with struct."""
    h = DIGEST_SEED
    for values in steps:
        for value in values:
            (word,) = struct.unpack("<Q", struct.pack("<d", value))
            h = ((h ^ word) * FNV_PRIME) % 2**64
    return h


def test_fold_is_the_documented_definition():
    rng = np.random.default_rng(7)
    t = np.arange(1, 6) * 1e-3
    q, w = rng.normal(size=(5, 4)), rng.normal(size=(5, 3))
    expected = _reference([(t[i], *q[i], *w[i]) for i in range(5)])
    assert fold_steps(DIGEST_SEED, t, q, w) == expected
    # folding in two pieces is folding at once
    assert fold_steps(fold_steps(DIGEST_SEED, t[:2], q[:2], w[:2]), t[2:], q[2:], w[2:]) == expected
    assert format_digest(expected) == f"{expected:016x}" and len(format_digest(1)) == 16


def test_one_bit_anywhere_changes_the_digest():
    t, q, w = np.array([0.001]), np.array([[0.0, 0.0, 0.0, 1.0]]), np.array([[0.1, 0.2, 0.3]])
    base = fold_steps(DIGEST_SEED, t, q, w)
    w2 = w.copy()
    w2[0, 2] = np.nextafter(w2[0, 2], 1.0)
    assert fold_steps(DIGEST_SEED, t, q, w2) != base


def test_the_simulator_digest_covers_every_step_whatever_the_chunks():
    scene = parse_scene_text(
        "body: {principal_moments: [1.0, 2.0, 3.0]}\n"
        "initial: {angular_velocity: [0.1, 1.0, 0.01]}\n"
        "integrator: {method: rk4, dt: 0.01}\n"
    )
    one, chunked = Simulator(scene), Simulator(scene)
    steps = []
    for _ in range(10):
        one.advance(1)
        integrator = one.stepper.integrator
        steps.append((one.clock.t, *integrator.q, *integrator.omega))
    chunked.advance(3)
    chunked.advance(7)
    assert one.snapshot().digest == chunked.snapshot().digest == _reference(steps)

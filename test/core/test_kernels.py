"""The compiled kernels: chunking does not change a bit, the cache works cold and is reused."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from rigid_rot_sim.core.integrators import METHODS
from rigid_rot_sim.core.torque import ConstantTorque, GravityTorque, PolynomialTorque

MOMENTS = np.array([1.0, 2.0, 3.0])
OMEGA0 = np.array([1.0, 0.1, 0.5])
Q0 = np.array([0.1, -0.2, 0.3, 0.9]) / np.linalg.norm([0.1, -0.2, 0.3, 0.9])

TORQUES = {
    "free": None,
    "constant": ConstantTorque(np.array([0.1, -0.05, 0.02])),
    "polynomial": PolynomialTorque(np.array([[0.1, -0.05, 0.02], [0.03, 0.0, -0.01], [0.0, 0.002, 0.0]])),
    "gravity": GravityTorque(np.array([0.0, 0.05, 0.1]), 2.0),
    "callable": lambda t, q, omega: np.array([0.01 * t, -0.02 * omega[0], 0.03 * q[3]]),
}


def variants():
    for name in METHODS:
        if name == "dop853":  # scipy's adaptive solver: stepped one at a time by the simulator
            continue
        orders = METHODS[name].orders
        for options in [{"order": o} for o in orders] if len(orders) > 1 else [{}]:
            yield name, options


@pytest.mark.parametrize("torque_name", list(TORQUES))
@pytest.mark.parametrize("name, options", list(variants()))
def test_chunked_steps_equal_single_steps_bit_for_bit(name, options, torque_name):
    torque = TORQUES[torque_name]
    dt = 0.0123

    def make():
        return METHODS[name](MOMENTS, dt, torque, q0=Q0, omega0=OMEGA0, t0=0.37, **options)

    try:
        single = make()
    except ValueError:  # exact refuses a torque; taylor refuses a callable
        return
    chunked = make()
    for _ in range(40):
        single.step()
    for chunk in (1, 3, 7, 2, 11, 16):  # 40 steps in uneven chunks, as the node takes them
        chunked.advance(chunk)
    assert single.n_steps == chunked.n_steps == 40
    assert single.t == chunked.t
    assert np.array_equal(single.q, chunked.q), (single.q, chunked.q)
    assert np.array_equal(single.omega, chunked.omega), (single.omega, chunked.omega)
    # and the saving form takes the same steps
    saving = make()
    q, omega = saving.advance_saving(8, 5)
    assert np.array_equal(q[-1], single.q) and np.array_equal(omega[-1], single.omega)


def test_batch_bodies_equal_single_bodies_bit_for_bit():
    from rigid_rot_sim.core.batch import BATCH_METHODS, FREE_BODY_METHODS, advance_batch

    rng = np.random.default_rng(3)
    n = 6
    moments = np.sort(rng.uniform(0.5, 2.0, size=(n, 3)), axis=1)
    q0 = rng.normal(size=(n, 4))
    q0 /= np.linalg.norm(q0, axis=1)[:, None]
    omega0 = rng.normal(size=(n, 3))
    torque = 0.1 * rng.normal(size=(n, 3))
    torque[2] = 0.0  # a free body among them
    for method in BATCH_METHODS:
        q, omega = advance_batch(method, moments, q0, omega0, 0.01, 300, torque)
        for k in range(n):
            single = METHODS[method](moments[k], 0.01, ConstantTorque(torque[k]), q0=q0[k], omega0=omega0[k])
            single.advance(300)
            assert np.array_equal(single.q, q[k]) and np.array_equal(single.omega, omega[k]), (method, k)
    for method in FREE_BODY_METHODS:
        q, omega = advance_batch(method, moments, q0, omega0, 0.01, 300)
        for k in range(n):
            single = METHODS[method](moments[k], 0.01, q0=q0[k], omega0=omega0[k])
            single.advance(300)
            assert np.array_equal(single.q, q[k]) and np.array_equal(single.omega, omega[k]), (method, k)
        with pytest.raises(ValueError, match="exact_split"):
            advance_batch(method, moments, q0, omega0, 0.01, 3, torque)


# A fresh process integrates with the cache directory given; it reports the state it reached
# and whether the fixed-step loop was compiled there or loaded from the cache.
_CHILD = textwrap.dedent(
    """
    import json
    import numpy as np
    from rigid_rot_sim.core.integrators import get_method, kernels
    from rigid_rot_sim.core.torque import ConstantTorque
    integrator = get_method("rk4")([1.0, 2.0, 3.0], 0.01, ConstantTorque([0.1, -0.05, 0.02]), omega0=[1.0, 0.1, 0.5])
    integrator.advance(100)
    stats = kernels.advance_compiled.stats
    print(json.dumps({
        "q": integrator.q.tolist(), "omega": integrator.omega.tolist(),
        "hits": sum(stats.cache_hits.values()), "misses": sum(stats.cache_misses.values()),
    }))
    """
)


def _run_child(cache_dir):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache_dir))
    result = subprocess.run([sys.executable, "-c", _CHILD], env=env, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def cold_cache(tmp_path_factory):
    cache_dir = tmp_path_factory.mktemp("numba_cache")
    return cache_dir, _run_child(cache_dir)


def _in_process_rk4():
    integrator = METHODS["rk4"](MOMENTS, 0.01, ConstantTorque(np.array([0.1, -0.05, 0.02])), omega0=OMEGA0)
    integrator.advance(100)
    return integrator


def test_cold_cache_start_compiles_and_gives_the_same_bits(cold_cache):
    cache_dir, cold = cold_cache
    assert cold["misses"] >= 1 and cold["hits"] == 0  # compiled there, from nothing
    assert list(cache_dir.rglob("*.nbi")) and list(cache_dir.rglob("*.nbc"))  # and written to the cache
    here = _in_process_rk4()
    assert cold["q"] == here.q.tolist() and cold["omega"] == here.omega.tolist()


def test_kernel_compiled_in_one_process_is_reused_by_the_next(cold_cache):
    cache_dir, cold = cold_cache
    warm = _run_child(cache_dir)
    assert warm["hits"] >= 1 and warm["misses"] == 0
    assert warm["q"] == cold["q"] and warm["omega"] == cold["omega"]


def test_cache_is_keyed_on_every_core_source(tmp_path, monkeypatch):
    """Editing a helper module (not the entry point's file) must invalidate the cache."""
    import shutil

    from rigid_rot_sim.core import jit
    from rigid_rot_sim.core.integrators import kernels

    locator = kernels.advance_compiled._cache._impl.locator
    assert isinstance(locator, (jit._CoreInTreeLocator, jit._CoreUserDirLocator))
    assert locator.get_source_stamp() == jit.sources_fingerprint()

    copy = tmp_path / "core"
    shutil.copytree(jit._CORE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(jit, "_CORE", copy)
    jit.sources_fingerprint.cache_clear()
    try:
        before = jit.sources_fingerprint()
        helper = copy / "quaternion.py"
        helper.write_text(helper.read_text() + "\n# edited\n")
        jit.sources_fingerprint.cache_clear()
        assert jit.sources_fingerprint() != before
    finally:
        jit.sources_fingerprint.cache_clear()


def test_fastmath_is_refused():
    from rigid_rot_sim.core.jit import compiled

    with pytest.raises(ValueError, match="fastmath"):
        compiled(lambda x: x, fastmath=True)

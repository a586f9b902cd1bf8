"""One name per formula: a method name means the same integrator in every registry and every model.

Before issue 28 ``rk4`` named RK4 in exponential coordinates (RKMK) in ``METHODS`` and the classical
RK4 on (q, omega, Omega) with renormalisation in ``GYROSTAT_METHODS``: a scene's ``integrator.method``
meant one or the other depending on its ``actuators:`` section.
"""

from pathlib import Path

import pytest

from rigid_rot_sim.core.batch import BATCH_METHODS, FREE_BODY_METHODS
from rigid_rot_sim.core.integrators import METHODS
from rigid_rot_sim.core.integrators.gyrostat import GYROSTAT_METHODS
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import load_scene

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"


def test_no_name_is_in_both_the_rigid_body_and_the_gyrostat_registry():
    assert not set(METHODS) & set(GYROSTAT_METHODS)


def test_the_batch_methods_are_the_rigid_body_methods_of_the_same_names():
    """core/batch runs the single-body kernels of the same names (bit for bit: test_batch.py)."""
    assert set(BATCH_METHODS + FREE_BODY_METHODS) <= set(METHODS)


@pytest.mark.parametrize("registry", [METHODS, GYROSTAT_METHODS], ids=["rigid body", "gyrostat"])
def test_every_integrator_calls_itself_by_its_registry_name(registry):
    """The start-up line and the recording name ``Simulator.method``, the integrator's own name."""
    assert {name: cls.name for name, cls in registry.items()} == {name: name for name in registry}


def test_a_spacecraft_scene_refuses_the_rigid_body_rk4_and_names_the_gyrostat_methods():
    scene = load_scene(str(SCENES / "wheel_slew.yaml"))  # reaction wheels: the gyrostat
    with pytest.raises(ValueError, match="valid methods: dopri5, gyrostat_rk4"):
        Simulator(scene, method="rk4")
    assert Simulator(scene, method="gyrostat_rk4").stepper.method == "gyrostat_rk4"

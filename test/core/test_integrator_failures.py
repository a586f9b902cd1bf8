"""Every method fails the same documented way (issue 9, item 12): a step that goes wrong raises
NonFiniteStateError, chained to what went wrong, and leaves the last good state."""

import math

import numpy as np
import pytest

from rigid_rot_sim.core.integrators import METHODS, NonFiniteStateError
from rigid_rot_sim.core.integrators.base import Integrator
from rigid_rot_sim.core.integrators.fixed_step import FixedStepIntegrator
from rigid_rot_sim.core.torque import ConstantTorque

MOMENTS = [1.0, 2.0, 3.0]

# (method, dt, |omega| scale): each raised a bare ValueError ("math domain error"),
# ZeroDivisionError or OverflowError from inside its step before
ABSURD = [
    ("splitting", 1e306, 1e10),  # sin(inf): math domain error
    ("implicit_midpoint", 1e150, 1.0),  # float division by zero
    ("exact", 1e306, 1e10),  # cannot convert float infinity to integer
    ("exact_split", 1e306, 1e10),
]


@pytest.mark.parametrize("method, dt, scale", ABSURD)
def test_absurd_step_raises_non_finite_state_error_and_keeps_the_last_good_state(method, dt, scale):
    omega0 = [scale, 0.5 * scale, 0.1]
    integrator = METHODS[method](MOMENTS, dt, omega0=omega0)
    with pytest.raises(NonFiniteStateError) as info:
        integrator.advance(3)
    assert method in str(info.value)
    assert np.all(np.isfinite(integrator.q)) and np.all(np.isfinite(integrator.omega))
    assert integrator.n_steps == 0 and integrator.omega.tolist() == omega0


@pytest.mark.parametrize("method", sorted(set(METHODS) - {"dop853", "taylor"}))
def test_every_method_reports_divergence_as_non_finite_state_error(method):
    integrator = METHODS[method](MOMENTS, 1e306, omega0=[1e10, 5e9, 0.1])
    with pytest.raises(NonFiniteStateError):
        for _ in range(5):
            integrator.step()
    assert np.all(np.isfinite(integrator.omega))


class _KernelRaising(FixedStepIntegrator):
    """Stands for a fixed-step loop whose kernel fails with a math error of its own."""

    name = "kernel_raising"
    kernel_name = "rk4"

    def _run(self, n, save_every):
        return math.sqrt(-1.0)


class _StepRaising(Integrator):
    """A method overriding advance itself (as a compiled loop would)."""

    name = "step_raising"

    def _step_impl(self):
        self.omega = self.omega * 2.0  # a partial update: step() must restore the state
        raise ZeroDivisionError("float division by zero")

    def advance(self, n):
        raise OverflowError("math range error")


@pytest.mark.parametrize("cls", [_KernelRaising, _StepRaising])
def test_the_rule_holds_for_subclasses_that_override_the_loop(cls):
    integrator = cls(MOMENTS, 0.01, omega0=[1.0, 0.0, 0.0])
    for call in (lambda: integrator.advance(2), integrator.step, lambda: integrator.advance_saving(1, 1)):
        with pytest.raises(NonFiniteStateError) as info:
            call()
        assert isinstance(info.value.__cause__, ArithmeticError | ValueError)
    assert integrator.omega.tolist() == [1.0, 0.0, 0.0]


class _Doubling(Integrator):
    """A method giving only ``_step_impl``: the base class loops, counts and checks it."""

    name = "doubling"

    def _step_impl(self):
        self.omega = self.omega * 2.0
        self.t = self.t + self.dt
        if self.omega[0] == 4.0:
            raise ZeroDivisionError("float division by zero")  # after a partial update
        if self.omega[0] > 5.0:
            self.omega = self.omega * math.inf  # a non-finite state, caught after the step


def test_the_base_loop_counts_checks_and_restores_a_step_impl():
    integrator = _Doubling(MOMENTS, 0.5, omega0=[1.0, 0.0, 0.0])
    integrator.step()
    assert integrator.n_steps == 1 and integrator.omega.tolist() == [2.0, 0.0, 0.0] and integrator.t == 0.5
    with pytest.raises(NonFiniteStateError) as info:
        integrator.advance(3)  # 4.0: the step raises; the state is the one before it
    assert isinstance(info.value.__cause__, ZeroDivisionError)
    assert integrator.n_steps == 1 and integrator.omega.tolist() == [2.0, 0.0, 0.0] and integrator.t == 0.5
    integrator.set_state(0.0, [0.0, 0.0, 0.0, 1.0], [3.0, 0.0, 0.0])
    with pytest.raises(NonFiniteStateError, match="non-finite state at step 2"):
        integrator.step()  # 6.0 -> inf: counted, then refused


@pytest.mark.parametrize("method", sorted(METHODS))
def test_step_is_one_counted_step_with_the_bits_of_advance_one(method):
    torque = None if method == "exact" else ConstantTorque(np.array([0.01, -0.02, 0.03]))
    stepped = METHODS[method](MOMENTS, 0.05, torque, omega0=[0.3, 1.0, -0.2])
    advanced = METHODS[method](MOMENTS, 0.05, torque, omega0=[0.3, 1.0, -0.2])
    for k in range(1, 4):
        stepped.step()
        advanced.advance(1)
        assert stepped.n_steps == advanced.n_steps == k
        assert stepped.t == advanced.t and stepped.q.tolist() == advanced.q.tolist()
        assert stepped.omega.tolist() == advanced.omega.tolist()

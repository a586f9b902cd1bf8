"""The gyrostat work-precision problem (P5) and the fast-wheel stability case: references and behaviour."""

import numpy as np

from rigid_rot_sim.analysis.metrics import omega_error
from rigid_rot_sim.analysis.problems import P5
from rigid_rot_sim.analysis.stability import run_case
from rigid_rot_sim.analysis.stability_cases import catalogue


def test_p5_reference_is_certified_and_rk4_converges_to_it_at_fourth_order():
    ref = P5.reference()
    assert 0.0 < ref.certified_to <= 1e-10
    errors = [omega_error(ref.omega, P5.final_state("gyrostat_rk4", dt)[1]) for dt in (0.02, 0.01)]
    assert 0.85 * 16 < errors[0] / errors[1] < 1.3 * 16, errors


def test_methods_without_wheels_are_refused_on_p5():
    try:
        P5.final_state("taylor", 0.01)
    except ValueError as exc:
        assert "cannot run wheels" in str(exc)
    else:
        raise AssertionError("taylor ran a gyrostat it cannot represent")


def test_fast_wheel_case_rk4_stays_stable_and_conserves_total_energy_and_momentum():
    case = next(c for c in catalogue(quick=True) if c.name == "fast wheel, slow body")
    run = run_case(case, "gyrostat_rk4")
    assert run.status == "stable"
    assert run.energy_drift < 1e-6 and run.momentum_drift < 1e-6
    assert np.isfinite(run.omega_error)
    assert run_case(case, "splitting").status == "refused"

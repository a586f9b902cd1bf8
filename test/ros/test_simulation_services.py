"""rigid_rot_sim.ros.simulation_services without DDS: constants under either spelling of the package."""

import pytest

from rigid_rot_sim.ros import simulation_services
from rigid_rot_sim.ros.simulation_services import _constant


class _Prefixed:
    RESULT_OK = 1


class _Plain:
    OK = 1


def test_constants_are_found_under_either_name():
    assert _constant(_Prefixed, "OK", "RESULT_") == 1 and _constant(_Plain, "OK", "RESULT_") == 1
    with pytest.raises(AttributeError, match="neither RESULT_NOT_FOUND nor NOT_FOUND"):
        _constant(_Plain, "NOT_FOUND", "RESULT_")


def test_the_installed_package_gives_the_standard_values():
    from simulation_interfaces.srv import ResetSimulation  # an exec_depend: missing means a broken install

    s = simulation_services
    assert (s.FEATURE_UNSUPPORTED, s.OK, s.INCORRECT_STATE, s.OPERATION_FAILED) == (0, 1, 3, 4)
    assert (s.STOPPED, s.PLAYING, s.PAUSED, s.QUITTING) == (0, 1, 2, 3)
    request = ResetSimulation.Request
    if hasattr(request, "SCOPE_TIME"):
        assert (
            request.SCOPE_DEFAULT,
            request.SCOPE_TIME,
            request.SCOPE_STATE,
            request.SCOPE_SPAWNED,
            request.SCOPE_ALL,
        ) == (s.SCOPE_DEFAULT, s.SCOPE_TIME, s.SCOPE_STATE, s.SCOPE_SPAWNED, s.SCOPE_ALL)

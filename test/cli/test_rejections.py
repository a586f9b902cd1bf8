"""The topic a RejectedCommand's source names, as rigid-rot torque matches it to its own commands."""

import pytest

from rigid_rot_sim.cli.rejections import resolve_source


@pytest.mark.parametrize(
    "source, namespace, name, topic",
    [
        ("~/torque", "/", "rigid_rot_sim", "/rigid_rot_sim/torque"),
        ("~/torque", "/robot1", "sim", "/robot1/sim/torque"),
        ("cmd", "/robot1", "sim", "/robot1/cmd"),
        ("cmd", "/", "sim", "/cmd"),
        ("/abs/cmd", "/robot1", "sim", "/abs/cmd"),
    ],
)
def test_a_source_resolves_as_the_node_resolved_its_topic(source, namespace, name, topic):
    assert resolve_source(source, namespace, name) == topic

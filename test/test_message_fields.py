"""The ROS-free message readers: duck-typed, so recordings read without rclpy get the same numbers."""

import subprocess
import sys
from types import SimpleNamespace as Fields

import numpy as np

from rigid_rot_sim import message_fields


def test_readers_take_any_object_with_the_message_fields():
    assert message_fields.time_to_seconds(Fields(sec=3, nanosec=250_000_000)) == 3.25
    assert np.array_equal(message_fields.vector3_to_array(Fields(x=1, y=-2.5, z=0.0)), [1.0, -2.5, 0.0])
    q = message_fields.quaternion_to_array(Fields(x=0.0, y=0.0, z=0.6, w=0.8))
    assert q.dtype == float and np.array_equal(q, [0.0, 0.0, 0.6, 0.8])


def test_the_readers_import_no_ros():
    code = (
        "import sys, rigid_rot_sim.message_fields; "
        "print(sorted(m for m in sys.modules if m.startswith(('rclpy', 'rigid_rot_msgs', 'geometry_msgs'))))"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True)
    assert result.stdout.strip() == "[]"


def test_conversions_offers_the_same_readers():
    from rigid_rot_sim import conversions

    assert conversions.state_to_arrays is message_fields.state_to_arrays
    assert conversions.time_to_seconds is message_fields.time_to_seconds

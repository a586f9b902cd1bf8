"""``rigid-rot mtb NAME=DIPOLE ...``: command torque rods (magnetorquers) of a running node.

    rigid-rot mtb mtq_x=0.1 mtq_z=-0.05           # A*m^2, by rod name; rods not named keep their dipole

Publishes one ``sensor_msgs/JointState`` on ``~/magnetorquer_command``: ``name`` the rods, ``effort`` their
dipoles (A*m^2), as ros2_control's topic interface sends joint commands (docs/spacecraft.md says why this
type). A dipole beyond a rod's max_dipole is clamped and said on ``~/sim_events``; a refused command (an
unknown rod, a scene without rods) ends it with the node's reason as one line on stderr and exit code 2
(:mod:`.actuator_send`).
"""

from __future__ import annotations

import argparse
import math

from rigid_rot_sim.cli.actuator_send import add_common_arguments, send

DEFAULT_TOPIC = "/rigid_rot_sim/magnetorquer_command"


def rod_dipole(text: str) -> tuple[str, float]:
    """``NAME=VALUE`` -> (name, dipole A*m^2); argparse's error for anything else."""
    name, sep, value = text.partition("=")
    try:
        dipole = float(value)
    except ValueError:
        dipole = math.nan
    if not sep or not name.strip() or not math.isfinite(dipole):
        raise argparse.ArgumentTypeError(f"expected NAME=DIPOLE with a finite dipole in A*m^2, got {text!r}")
    return name.strip(), dipole


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "mtb", help="command torque rods (magnetorquers) of a running node", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("dipoles", nargs="+", type=rod_dipole, metavar="NAME=DIPOLE", help="rod name and A*m^2")
    add_common_arguments(parser, DEFAULT_TOPIC)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    names = [name for name, _ in args.dipoles]
    if len(set(names)) != len(names):
        raise ValueError(f"a rod is named twice: {names}")
    from sensor_msgs.msg import JointState

    message = JointState()
    message.name = names
    message.effort = [dipole for _, dipole in args.dipoles]
    described = ", ".join(f"{name}={dipole:g}" for name, dipole in args.dipoles)
    return send(args, "rigid_rot_mtb", JointState, message, f"rod dipoles {described} A*m^2")

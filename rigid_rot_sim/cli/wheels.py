"""``rigid-rot wheels T1 T2 ...``: set the reaction wheels' motor torques of a running node.

    rigid-rot wheels 0.001 0 -0.002               # N*m, one per wheel in the scene's order
    rigid-rot wheels --zero 3                     # three wheels, all zero

Publishes one ``rigid_rot_msgs/WheelTorques`` on ``~/wheel_torque`` (the node holds it until the next;
a value beyond a wheel's max_torque is clamped and said on ``~/sim_events``). A refused command (a wrong
number of values, a scene without wheels) ends it with the node's reason as one line on stderr and exit
code 2 (:mod:`.actuator_send`).
"""

from __future__ import annotations

import argparse

from rigid_rot_sim.cli.actuator_send import add_common_arguments, send
from rigid_rot_sim.cli.argtypes import finite_number, positive_integer

DEFAULT_TOPIC = "/rigid_rot_sim/wheel_torque"


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "wheels", help="set the reaction wheels' motor torques of a running node", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("torques", nargs="*", type=finite_number, metavar="T", help="motor torque per wheel, N*m")
    parser.add_argument("--zero", type=positive_integer, metavar="N", help="send N zero torques (clears the wheels)")
    add_common_arguments(parser, DEFAULT_TOPIC)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    if args.zero is not None:
        if args.torques:
            raise ValueError("--zero N takes no torque values")
        torques = [0.0] * args.zero
    elif not args.torques:
        raise ValueError("give one motor torque per wheel (N*m), or --zero N")
    else:
        torques = list(args.torques)
    from rigid_rot_msgs.msg import WheelTorques

    message = WheelTorques()
    message.torques = torques
    return send(args, "rigid_rot_wheels", WheelTorques, message, f"wheel torques {torques} N*m")

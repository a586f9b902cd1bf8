"""``rigid-rot run SCENE``: start the simulation node on a scene from the shell.

    rigid-rot run config/scenes/free_tumble.yaml --duration 3 --echo 0.5
    rigid-rot run torque_driven --realtime-factor 0 --record out.mcap
    rigid-rot run heavy_top --ros-args --params-file config/params/example.yaml

SCENE is a path, or the name of a scene shipped in config/scenes (found through the ament
index: the installed share directory, or the checkout when not installed). The options become
node parameters (``scene``, ``duration``, ``real_time_factor``, ``integrator``, ``dt``,
``record_path``, ``record_log_time``, ``foxglove``, ``web``); anything after ``--ros-args`` goes to ROS
unchanged, so a params file, ``-p`` or remappings work as with ``ros2 run``. An option given on the
command line wins over a params file's value (said on stderr), as an explicit argument does in
ROS tools; the same parameter given again with ``-p`` is refused (exit code 2, naming both).
``--echo PERIOD`` adds a subscriber
in the same process that prints the received ~/state every PERIOD s of sim time: what
the node published, through DDS. Exit code 0 when the duration is reached or on Ctrl-C.
"""

from __future__ import annotations

import argparse
import itertools
import os
import sys
from typing import TYPE_CHECKING, Any

import yaml

from rigid_rot_sim.cli.argtypes import nonnegative_number, positive_number
from rigid_rot_sim.cli.ros_args import add_ros_args
from rigid_rot_sim.recording import LOG_TIME_BASES
from rigid_rot_sim.share import resolve_scene, scene_search_dirs  # noqa: F401 (both: API of this module)

if TYPE_CHECKING:
    from rclpy.parameter import Parameter


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "run",
        help="run the simulation node on a scene",
        description=__doc__.split("\n\n")[0],
    )
    parser.add_argument("scene", help="scene YAML path, or a shipped scene name (e.g. free_tumble)")
    parser.add_argument("--duration", type=nonnegative_number, help="sim seconds to run, then exit 0 (0 = unbounded)")
    parser.add_argument(
        "--realtime-factor",
        type=nonnegative_number,
        dest="real_time_factor",
        help="1 = wall-clock pace, 0 = as fast as possible",
    )
    parser.add_argument("--integrator", help="integrator name from the registry, or auto")
    parser.add_argument("--dt", type=positive_number, help="physics step, s")
    parser.add_argument("--record", metavar="OUT.mcap", help="record the run to this MCAP file")
    parser.add_argument(
        "--record-log-time",
        choices=LOG_TIME_BASES,
        dest="record_log_time",
        help="MCAP log times of the recording: sim time (default) or wall clock",
    )
    parser.add_argument(
        "--foxglove",
        metavar="[HOST:]PORT",
        help="serve the run live to Foxglove (WebSocket, host default 127.0.0.1); needs foxglove-sdk",
    )
    parser.add_argument(
        "--web",
        metavar="[HOST:]PORT",
        help="serve the body's web page (http, host default 127.0.0.1; any browser, offline); needs viser",
    )
    parser.add_argument(
        "--echo", type=positive_number, metavar="PERIOD", help="print the received ~/state every PERIOD s of sim time"
    )
    add_ros_args(parser)
    parser.set_defaults(handler=run)


def explicit_parameters(args: argparse.Namespace) -> dict[str, tuple[str, str | float]]:
    """The parameters given by ``rigid-rot run``'s own options: name -> (option, value).

    They win over ``--ros-args`` (a params file's value of the same name is overridden); the
    same parameter given again with ``-p`` is a conflict (:func:`check_conflicts`).
    """
    from rigid_rot_sim.ros import parameters as p  # the names, from the node's table (imports rclpy)

    options: list[tuple[str, p.ParamSpec[Any], str | float | None]] = [
        ("SCENE", p.SCENE, resolve_scene(args.scene)),  # ValueError for an unknown scene, before ROS starts
        ("--duration", p.DURATION, None if args.duration is None else float(args.duration)),
        (
            "--realtime-factor",
            p.REAL_TIME_FACTOR,
            None if args.real_time_factor is None else float(args.real_time_factor),
        ),
        ("--integrator", p.INTEGRATOR, args.integrator),
        ("--dt", p.DT, None if args.dt is None else float(args.dt)),
        ("--record", p.RECORD_PATH, None if args.record is None else os.path.abspath(args.record)),
        ("--record-log-time", p.RECORD_LOG_TIME, args.record_log_time),
        ("--foxglove", p.FOXGLOVE, args.foxglove),
        ("--web", p.WEB, args.web),
    ]
    return {spec.name: (option, value) for option, spec, value in options if value is not None}


def _ros_parameter_rules(ros_args: list[str]) -> list[tuple[str, str]]:
    """The ``-p [node:]name:=value`` rules of ``ros_args``, as (name, rule)."""
    rules = []
    for flag, rule in itertools.pairwise(ros_args):
        if flag in ("-p", "--param") and ":=" in rule:
            rules.append((rule.split(":=", 1)[0].rsplit(":", 1)[-1], rule))
    return rules


def _params_file_names(path: str) -> set[str]:
    """The parameter names a params file gives any node (dotted for nested ones); empty if unreadable."""
    try:
        with open(path, encoding="utf-8") as stream:
            document = yaml.safe_load(stream)
    except (OSError, yaml.YAMLError):
        return set()  # the node reports it as rcl does
    names: set[str] = set()

    def walk(prefix: str, mapping: Any) -> None:
        for key, value in mapping.items():
            if isinstance(value, dict):
                walk(f"{prefix}{key}.", value)
            else:
                names.add(f"{prefix}{key}")

    for section in (document or {}).values() if isinstance(document, dict) else ():
        parameters = section.get("ros__parameters") if isinstance(section, dict) else None
        if isinstance(parameters, dict):
            walk("", parameters)
    return names


def check_conflicts(explicit: dict[str, tuple[str, str | float]], ros_args: list[str]) -> list[str]:
    """ValueError naming an option also given as ``-p``; the notes on params files' values the options override."""
    for name, rule in _ros_parameter_rules(ros_args):
        if name in explicit:
            option, value = explicit[name]
            shown = option if option == "SCENE" else f"{option} {value}"
            raise ValueError(f"{shown} and --ros-args -p {rule} both set the {name} parameter: give one")
    notes = []
    files = [path for flag, path in itertools.pairwise(ros_args) if flag == "--params-file"]
    for path in files:
        overridden = sorted(_params_file_names(path) & explicit.keys())
        if overridden:
            options = ", ".join(sorted({explicit[name][0] for name in overridden}, key=lambda o: (o != "SCENE", o)))
            notes.append(f"{options} override {path}'s {', '.join(overridden)} (the command line wins)")
    return notes


def node_arguments(args: argparse.Namespace) -> tuple[list[str], list[Parameter]]:
    """The node's argv (``--ros-args`` as given) and the options' parameters, which win over it.

    ValueError for an unknown scene or an option that ``-p`` gives again; a params file's
    value that an option overrides is said on stderr.
    """
    from rclpy.parameter import Parameter

    explicit = explicit_parameters(args)
    ros_args = list(args.ros_args or [])
    for note in check_conflicts(explicit, ros_args):
        print(f"rigid-rot run: {note}", file=sys.stderr, flush=True)
    argv = ["rigid_rot_sim_node", "--ros-args", *ros_args]
    return argv, [Parameter(name, value=value) for name, (_, value) in explicit.items()]


def run(args: argparse.Namespace) -> int:
    argv, overrides = node_arguments(args)  # ValueError for an unknown scene or a conflict, before ROS starts
    if args.echo is None:
        from rigid_rot_sim.ros.node import main

        return main(argv, overrides)
    return _run_with_echo(argv, overrides, args.echo)


def _run_with_echo(argv: list[str], overrides: list[Parameter], period: float) -> int:
    """The node plus a subscriber to its ~/state in one executor, printing every ``period`` s."""
    import rclpy
    from rclpy.node import Node

    from rigid_rot_msgs.msg import RigidBodyState
    from rigid_rot_sim import conversions
    from rigid_rot_sim.ros.node import RigidRotSimNode
    from rigid_rot_sim.ros.node_process import STARTUP_ERRORS, init_ros, run_until_finished
    from rigid_rot_sim.ros.qos import STATE_QOS

    try:
        init_ros(argv)
    except RuntimeError as exc:  # rclpy's RCLError: an unparsable --ros-args rule
        raise ValueError(f"bad ROS arguments: {exc}") from None
    next_print = [0.0]
    received = [0]
    state_topic = ""

    def on_state(msg: RigidBodyState) -> None:
        received[0] += 1
        s = conversions.state_to_arrays(msg)
        if s["t"] + 1e-9 < next_print[0]:
            return
        next_print[0] = s["t"] + period
        q, w = s["orientation"], s["angular_velocity_body"]
        print(
            f"t={s['t']:8.3f} s  q=({q[0]:+.4f} {q[1]:+.4f} {q[2]:+.4f} {q[3]:+.4f})  "
            f"w_body=({w[0]:+.4f} {w[1]:+.4f} {w[2]:+.4f}) rad/s  "
            f"|L|={float(sum(v * v for v in s['angular_momentum_world'])) ** 0.5:.6f}  "
            f"E={s['kinetic_energy'] + s['potential_energy']:.6f} J  "
            f"drift E={s['energy_drift']:+.1e} |L|={s['angular_momentum_drift']:+.1e}",
            flush=True,
        )

    def start(nodes: list[Node]) -> RigidRotSimNode:
        nonlocal state_topic
        node = RigidRotSimNode(parameter_overrides=overrides)
        nodes.append(node)
        echo = rclpy.create_node("rigid_rot_echo")
        nodes.append(echo)
        state_topic = node.resolve_topic_name("~/state")
        echo.create_subscription(RigidBodyState, state_topic, on_state, STATE_QOS)
        print(f"echo: printing {state_topic} every {period:g} s of sim time", flush=True)
        return node

    try:
        run_until_finished(start, drain=0.2)  # drain: let the last states arrive
    except STARTUP_ERRORS as exc:  # printed as one line by rigid-rot's main, exit code 2
        raise ValueError(str(exc)) from None
    if state_topic:
        print(f"echo: {received[0]} messages received on {state_topic}", flush=True)
    return 0

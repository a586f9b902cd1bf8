"""``rigid-rot inertia``: mass properties of point masses, locally or through the ROS 2 service.

Input is a body file (YAML, see ``config/bodies/sample_body.yaml``)::

    name: sample_satellite             # optional, defaults to the file stem
    frame_id: base_link                # optional, frame of the positions and results
    origin: [0, 0, 0]                  # optional, m, point inertia_origin is taken about
    point_masses:
      masses: [m, ...]                 # kg, each > 0
      positions: [[x, y, z], ...]      # m, one per mass

or repeated ``--mass M X Y Z`` options. ``--service NAME`` sends the same body to a running
node's ``~/compute_inertia`` over DDS and prints its answer instead; with ``--compare`` it
also checks that answer against the local computation (exit code 1 if they differ).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rigid_rot_sim.cli.ros_args import add_ros_args, rclpy_args
from rigid_rot_sim.core.inertia import MassProperties, mass_properties, principal_orientation
from rigid_rot_sim.core.limits import clip_text

DEFAULT_SERVICE = "/rigid_rot_sim/compute_inertia"
BODY_KEYS = ("name", "frame_id", "origin", "point_masses")


@dataclass(frozen=True)
class BodyInput:
    """Point masses to evaluate: masses (n,) kg, positions (n, 3) m, origin (3,) m."""

    name: str
    frame_id: str
    masses: np.ndarray
    positions: np.ndarray
    origin: np.ndarray


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "inertia",
        help="mass properties (inertia tensor, principal axes) of point masses",
        description=__doc__.split("\n\n")[0],
    )
    parser.add_argument("body_file", nargs="?", metavar="FILE.yaml", help="body file with point_masses")
    parser.add_argument(
        "--mass",
        action="append",
        nargs=4,
        type=float,
        metavar=("M", "X", "Y", "Z"),
        help="a point mass M (kg) at (X, Y, Z) (m); repeat for each mass (instead of FILE)",
    )
    parser.add_argument(
        "--origin",
        nargs=3,
        type=float,
        metavar=("X", "Y", "Z"),
        help="point (m) to take inertia_origin about (default: the file's, else 0 0 0)",
    )
    parser.add_argument("--frame-id", help="frame of positions and results (default: the file's)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument(
        "--service",
        nargs="?",
        const=DEFAULT_SERVICE,
        metavar="NAME",
        help=f"ask a running node's ComputeInertia service (default name {DEFAULT_SERVICE})",
    )
    parser.add_argument(
        "--compare", action="store_true", help="with --service: check the answer against the local computation"
    )
    parser.add_argument("--timeout", type=float, default=10.0, help="s to wait for the service (default 10)")
    add_ros_args(parser)
    parser.set_defaults(handler=run)


def load_body_file(path: str | os.PathLike) -> BodyInput:
    """Read a body file; ValueError naming the file and key when its structure is wrong.

    The numbers themselves (positive masses, finite positions, matching lengths) are
    checked by :func:`rigid_rot_sim.core.inertia.mass_properties`.
    """
    from rigid_rot_sim.scene.bounded_yaml import BoundedYAMLError, load_bounded, read_bounded

    path = Path(path)
    try:
        raw = load_bounded(read_bounded(path))  # size, depth, list lengths bounded; no aliases
    except BoundedYAMLError as exc:
        raise ValueError(f"{path}: {exc}") from None
    if not isinstance(raw, Mapping):
        raise ValueError(f"{path}: must be a mapping with a point_masses key")
    unknown = sorted(set(raw) - set(BODY_KEYS))
    if unknown:
        raise ValueError(f"{path}: unknown key {unknown[0]!r} (allowed: {', '.join(BODY_KEYS)})")
    block = raw.get("point_masses")
    if not isinstance(block, Mapping) or "masses" not in block or "positions" not in block:
        raise ValueError(f"{path}: point_masses must be a mapping with masses and positions")
    masses = _numbers(block["masses"], f"{path}: point_masses.masses", ndim=1)
    positions = _numbers(block["positions"], f"{path}: point_masses.positions", ndim=2)
    origin = _numbers(raw.get("origin", [0.0, 0.0, 0.0]), f"{path}: origin", ndim=1)
    return BodyInput(
        name=str(raw.get("name", path.stem)),
        frame_id=str(raw.get("frame_id", "")),
        masses=masses,
        positions=positions,
        origin=origin,
    )


def _numbers(value, where: str, ndim: int) -> np.ndarray:
    shown = clip_text(repr(value), 60)
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(
            f"{where} must be {'a list of numbers' if ndim == 1 else 'a list of [x, y, z]'}, got {shown}"
        ) from None
    if array.ndim != ndim or (ndim == 2 and array.shape[1] != 3):
        raise ValueError(f"{where} must be {'a list of numbers' if ndim == 1 else 'a list of [x, y, z]'}, got {shown}")
    return array


def body_from_args(args: argparse.Namespace) -> BodyInput:
    if args.body_file and args.mass:
        raise ValueError("give either FILE.yaml or --mass options, not both")
    if args.body_file:
        body = load_body_file(args.body_file)
    elif args.mass:
        table = np.array(args.mass, dtype=float)
        body = BodyInput("command line", "", table[:, 0], table[:, 1:], np.zeros(3))
    else:
        raise ValueError("no masses: give FILE.yaml or at least one --mass M X Y Z")
    if args.origin is not None:
        body = BodyInput(body.name, body.frame_id, body.masses, body.positions, np.array(args.origin))
    if args.frame_id is not None:
        body = BodyInput(body.name, args.frame_id, body.masses, body.positions, body.origin)
    return body


def run(args: argparse.Namespace) -> int:
    if args.compare and not args.service:
        raise ValueError("--compare needs --service")
    if args.ros_args is not None and not args.service:
        raise ValueError("--ros-args needs --service (only the service call creates a ROS node)")
    body = body_from_args(args)
    local = mass_properties(body.masses, body.positions, body.origin)
    if not args.service:
        print(format_json(body, local) if args.json else format_table(body, local))
        return 0
    remote = call_service(args.service, body, args.timeout, ros_args=rclpy_args(args))
    print(format_json(body, remote) if args.json else format_table(body, remote, source=args.service))
    if args.compare:
        difference = max_difference(local, remote)
        scale = max(float(local.principal_moments[-1]), float(local.total_mass), 1.0)
        if remote.symmetry != local.symmetry or not difference <= 1e-12 * scale:
            print(
                f"rigid-rot inertia: MISMATCH: service and library differ by {difference:.3g} "
                f"(symmetry {remote.symmetry} vs {local.symmetry})",
                file=sys.stderr,
            )
            return 1
        print(f"service answer matches the library (largest difference {difference:.3g})")
    return 0


def call_service(name: str, body: BodyInput, timeout: float, ros_args: list[str] | None = None) -> MassProperties:
    """Send ``body`` to a ComputeInertia service; the answer as MassProperties.

    ``ros_args``: the argv for rclpy (``[program, "--ros-args", ...]``: remappings, namespace).

    RuntimeError (exit code 1) if the service does not answer within ``timeout`` s;
    ValueError (exit code 2) if it rejects the request.
    """
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from rigid_rot_msgs.srv import ComputeInertia
    from rigid_rot_sim import conversions

    request = conversions.arrays_to_compute_inertia_request(body.masses, body.positions, body.origin, body.frame_id)
    context = rclpy.Context()
    rclpy.init(args=ros_args or [], context=context)
    try:
        node = rclpy.create_node("rigid_rot_inertia_client", context=context)
        client = node.create_client(ComputeInertia, name)
        if not client.wait_for_service(timeout_sec=timeout):
            raise SystemExit(
                f"{name}: no ComputeInertia service within {timeout:g} s "
                f"(ROS_DOMAIN_ID={os.environ.get('ROS_DOMAIN_ID', '0')})"
            )
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        future = client.call_async(request)
        executor.spin_until_future_complete(future, timeout_sec=timeout)
        if not future.done():
            raise SystemExit(f"{name}: no answer within {timeout:g} s")
        response = future.result()
    finally:
        rclpy.try_shutdown(context=context)
    if not response.success:
        raise ValueError(f"service rejected the request: {response.message}")
    return conversions.compute_inertia_response_to_mass_properties(response, body.origin)


def max_difference(a: MassProperties, b: MassProperties) -> float:
    """Largest absolute difference over every numeric field that has a unique value.

    The principal axes are compared through the tensor they diagonalise (eigenvectors of
    equal moments are not unique, and each axis is only defined up to sign).
    """
    rebuilt_b = b.principal_axes @ np.diag(b.principal_moments) @ b.principal_axes.T
    pairs = [
        (a.total_mass, b.total_mass),
        (a.center_of_mass, b.center_of_mass),
        (a.inertia_origin, b.inertia_origin),
        (a.inertia_com, b.inertia_com),
        (a.principal_moments, b.principal_moments),
        (a.inertia_com, rebuilt_b),
    ]
    return max(float(np.max(np.abs(np.asarray(x, dtype=float) - np.asarray(y, dtype=float)))) for x, y in pairs)


def as_dict(body: BodyInput, props: MassProperties) -> dict:
    return {
        "name": body.name,
        "frame_id": body.frame_id,
        "count": int(len(body.masses)),
        "total_mass": props.total_mass,
        "center_of_mass": props.center_of_mass.tolist(),
        "origin": props.origin.tolist(),
        "inertia_origin": props.inertia_origin.tolist(),
        "inertia_com": props.inertia_com.tolist(),
        "principal_moments": props.principal_moments.tolist(),
        "principal_axes": props.principal_axes.tolist(),
        "principal_orientation": principal_orientation(props.principal_axes).tolist(),
        "symmetry": props.symmetry,
    }


def format_json(body: BodyInput, props: MassProperties) -> str:
    return json.dumps(as_dict(body, props), indent=2)


def _row(values) -> str:
    return "  ".join(f"{float(v):+.9g}".rjust(16) for v in values)


def format_table(body: BodyInput, props: MassProperties, source: str = "library") -> str:
    frame = body.frame_id or "(unnamed frame)"
    quat = principal_orientation(props.principal_axes)
    lines = [
        f"body {body.name}: {len(body.masses)} point masses, frame {frame}, computed by {source}",
        f"  total mass             {props.total_mass:.9g} kg",
        f"  centre of mass         {_row(props.center_of_mass)}  m",
        f"  inertia about origin ({', '.join(f'{v:g}' for v in props.origin)}) m, kg*m^2:",
        *(f"                         {_row(r)}" for r in props.inertia_origin),
        "  inertia about centre of mass, kg*m^2:",
        *(f"                         {_row(r)}" for r in props.inertia_com),
        f"  principal moments      {_row(props.principal_moments)}  kg*m^2 (I1 <= I2 <= I3)",
        "  principal axes (columns e1 e2 e3, in frame):",
        *(f"                         {_row(r)}" for r in props.principal_axes),
        f"  principal orientation  {_row(quat)}  (x, y, z, w), principal -> frame",
        f"  symmetry               {props.symmetry}",
    ]
    return "\n".join(lines)

"""``rigid-rot identify BAG``: the inertia tensor (and biases) that make the simulation match a bag.

Reads gyro samples and torques from an MCAP file or a rosbag2 directory (ours without options),
fits Euler's equations to them (equation error, then output error with our integrator), prints
the tensor with its one-sigma uncertainty, and replays the bag with the nominal and the
identified inertia. The method and its limits: docs/identify.md.
"""

from __future__ import annotations

import argparse

from rigid_rot_sim.cli.argtypes import positive_number


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "identify",
        help="identify a body's inertia from a recorded run",
        description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("bag", metavar="BAG", help="an MCAP file or a rosbag2 directory")
    rate = parser.add_mutually_exclusive_group()
    rate.add_argument("--imu", metavar="TOPIC", help="sensor_msgs/Imu: angular_velocity (and orientation if given)")
    rate.add_argument("--angular-velocity", metavar="TOPIC", help="geometry_msgs/Vector3Stamped, rad/s, body frame")
    rate.add_argument("--state", metavar="TOPIC", help="rigid_rot_msgs/RigidBodyState")
    parser.add_argument(
        "--torque",
        metavar="TOPIC",
        action="append",
        default=[],
        help="geometry_msgs/WrenchStamped commands (repeatable, summed); header.frame_id: body or world frame",
    )
    parser.add_argument("--body-frame", action="append", default=[], metavar="NAME", help="another body frame name")
    parser.add_argument("--world-frame", action="append", default=[], metavar="NAME", help="another world frame name")
    parser.add_argument("--start", type=float, metavar="S", help="window start, s from the first sample")
    parser.add_argument("--end", type=float, metavar="S", help="window end, s from the first sample")
    parser.add_argument(
        "--estimate",
        default="inertia",
        metavar="LIST",
        help="comma-separated: inertia, torque_bias, gyro_bias (default: inertia)",
    )
    parser.add_argument("--nominal", metavar="BODY_OR_SCENE", help="the nominal inertia (default: the recorded scene)")
    parser.add_argument("--segment", type=positive_number, default=10.0, metavar="S", help="output-error segment, s")
    parser.add_argument("--plot", metavar="DIR", help="write the validation plots here")
    parser.add_argument("--out", metavar="BODY.yaml", help="write the identified body section here")
    parser.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    parser.set_defaults(handler=run)


def run(args) -> int:
    import json

    from rigid_rot_sim.identify.bag import BODY_FRAMES, WORLD_FRAMES, BagInputs, read_bag
    from rigid_rot_sim.identify.fit import identify
    from rigid_rot_sim.identify.nominal import load_nominal, recorded_nominal
    from rigid_rot_sim.identify.report import as_json, body_yaml, summary, validate

    estimate = [e.strip() for e in args.estimate.split(",") if e.strip()]
    if args.start is not None and args.end is not None and args.end <= args.start:
        raise ValueError(f"--end {args.end} must be after --start {args.start}")
    inputs = BagInputs(
        imu=args.imu,
        angular_velocity=args.angular_velocity,
        state=args.state,
        torque=tuple(args.torque),
        body_frames=BODY_FRAMES + tuple(args.body_frame),
        world_frames=WORLD_FRAMES + tuple(args.world_frame),
    )
    data = read_bag(args.bag, inputs)
    nominal = load_nominal(args.nominal) if args.nominal else recorded_nominal(data.scene_text)
    measurements = data.measurements.window(args.start, args.end)
    result = identify(measurements, estimate=estimate, segment=args.segment)
    validation = validate(measurements, result, nominal)
    if args.out:
        with open(args.out, "w", encoding="utf-8") as f:
            f.write(body_yaml(result))
    if args.plot:
        from rigid_rot_sim.identify.plot import plot_validation

        plot_validation(measurements, validation, args.plot)
    if args.json:
        print(json.dumps(as_json(result, validation, data.sources)))
    else:
        print(f"{args.bag}: rate from {data.sources['rate']}, torque from {data.sources['torque']}")
        print(summary(result, validation))
    return 0

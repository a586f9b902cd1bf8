"""``rigid-rot export aem BAG [--out FILE]``: a recording's attitude history for spacecraft tools.

Writes a CCSDS Attitude Ephemeris Message (AEM 2.0, CCSDS 504.0-B-2, KVN) with one data line
per recorded state: REF_FRAME_A an inertial frame (EME2000 by default) for the run's world
frame, REF_FRAME_B a spacecraft body frame (SC_BODY_1) for its body frame, time tags from the
scene's ``epoch`` (UTC) plus sim time. GMAT, Orekit and STK read it.
"""

from __future__ import annotations


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "export", help="export a recording to another format (CCSDS AEM)", description=__doc__.split("\n\n")[0]
    )
    formats = parser.add_subparsers(dest="format", metavar="FORMAT", required=True)
    aem = formats.add_parser("aem", help="CCSDS Attitude Ephemeris Message 2.0 (KVN)", description=__doc__)
    aem.add_argument("bag", metavar="BAG.mcap")
    aem.add_argument("--out", metavar="FILE", help="output file (default: BAG with the suffix .aem)")
    aem.add_argument(
        "--ref-frame-a",
        default="EME2000",
        metavar="NAME",
        help="inertial frame name for the run's world frame (default EME2000)",
    )
    aem.add_argument(
        "--ref-frame-b",
        default="SC_BODY_1",
        metavar="NAME",
        help="spacecraft body frame name for the run's body frame (default SC_BODY_1)",
    )
    aem.add_argument(
        "--angvel",
        action="store_true",
        help="ATTITUDE_TYPE QUATERNION/ANGVEL: add the body rates (deg/s, ANGVEL_FRAME = REF_FRAME_B)",
    )
    aem.add_argument("--object-name", metavar="NAME", help="OBJECT_NAME (default: the scene's name, upper case)")
    aem.add_argument("--object-id", default="UNKNOWN", metavar="ID", help="OBJECT_ID (default UNKNOWN)")
    parser.set_defaults(handler=run)


def run(args) -> int:
    from rigid_rot_sim.recording.aem import AemOptions, write_aem

    options = AemOptions(
        ref_frame_a=args.ref_frame_a,
        ref_frame_b=args.ref_frame_b,
        angular_velocity=args.angvel,
        object_name=args.object_name,
        object_id=args.object_id,
    )
    target = write_aem(args.bag, args.out, options.checked())
    print(f"wrote {target}")
    return 0

"""``rigid-rot bag``: inspect a recording, or repair one cut short by a crash.

``rigid-rot bag info FILE`` prints topics, message counts, QoS, scene and integrator
(the file's own summary, like ``ros2 bag info``). ``rigid-rot bag repair FILE`` rewrites a
file left without summary by SIGKILL or power loss (everything up to the last flushed
chunk, at most one second before the crash), keeping the original as ``FILE.crashed``.
"""

from __future__ import annotations


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "bag", help="inspect or repair an MCAP recording", description=__doc__.split("\n\n")[0]
    )
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    info = actions.add_parser("info", help="summary of a recording")
    info.add_argument("file", metavar="FILE.mcap")
    info.set_defaults(handler=run_info)
    repair = actions.add_parser("repair", help="rewrite a crashed recording with a complete index")
    repair.add_argument("file", metavar="FILE.mcap")
    repair.add_argument("-o", "--output", metavar="OUT.mcap", help="write here instead of replacing FILE")
    repair.add_argument("--no-backup", action="store_true", help="do not keep the original as FILE.crashed")
    repair.set_defaults(handler=run_repair)


def run_info(args) -> int:
    from rigid_rot_sim.recording.reader import info

    print(info(args.file))
    return 0


def run_repair(args) -> int:
    from rigid_rot_sim.recording.reader import repair

    report = repair(args.file, args.output, backup=not args.no_backup)
    if report.already_complete:
        print(f"{args.file}: already complete (summary present); nothing to do")
        return 0
    lost = ""
    if report.bad_chunks or report.unread_bytes:
        lost = f"; dropped {report.bad_chunks} torn chunk(s) and {report.unread_bytes} trailing bytes"
    print(f"repaired: {report.output} holds {report.messages} messages from {report.chunks} chunk(s){lost}")
    if report.backup is not None:
        print(f"original kept as {report.backup}")
    return 0

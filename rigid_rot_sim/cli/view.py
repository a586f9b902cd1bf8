"""``rigid-rot view BAG --foxglove [HOST:]PORT``: serve a recording to Foxglove, without ROS.

Open Foxglove (the desktop app, or app.foxglove.dev), Open connection -> Foxglove WebSocket,
``ws://127.0.0.1:PORT``: the recording plays at its own pace (play, pause, seek and speed from
the app's playback bar), with the body as a 3D scene entity (inertia box, omega and L arrows)
on ``/rigid_rot_sim/body_scene``. Ctrl-C stops serving. Needs foxglove-sdk
(``pip install rigid_rot_sim[viewer]``; ``make setup`` installs it).
"""

from __future__ import annotations


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "view", help="serve a recording to Foxglove (WebSocket, no ROS)", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("bag", metavar="BAG.mcap")
    parser.add_argument(
        "--foxglove",
        metavar="[HOST:]PORT",
        default="8765",
        help="where to serve (default 8765 on 127.0.0.1; 0: any free port)",
    )
    parser.add_argument("--speed", type=float, default=1.0, help="initial playback speed (default 1)")
    parser.add_argument("--once", action="store_true", help="exit when the end is reached (default: serve on)")
    parser.set_defaults(handler=run)


def run(args) -> int:
    import signal

    from rigid_rot_sim.viewer.foxglove import available, parse_address

    host, port = parse_address(args.foxglove)
    if not available():
        raise ValueError("foxglove-sdk is not installed (pip install rigid_rot_sim[viewer])")
    if not args.speed > 0.0:
        raise ValueError(f"--speed must be > 0, got {args.speed}")
    from rigid_rot_sim.viewer.playback import RecordingPlayer

    try:
        player = RecordingPlayer(args.bag, host, port, speed=args.speed)
    except RuntimeError as exc:  # foxglove-sdk: the port is taken
        raise ValueError(f"cannot serve on {args.foxglove}: {exc}") from None
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: player.stop())
    print(f"serving {args.bag} to Foxglove at ws://{host}:{player.port} (Ctrl-C stops)", flush=True)
    try:
        player.play(once=args.once)
    finally:
        player.close()
    return 0

"""``rigid-rot view BAG [--web [HOST:]PORT] [--foxglove [HOST:]PORT]``: show a recording, without ROS.

``--web PORT``: open ``http://127.0.0.1:PORT/`` in any browser (no internet needed): the body
turning, omega and L, the plots, and play / pause / speed / a time slider; playback starts when
the first browser connects. Needs viser (``pip install rigid_rot_sim[web]``).
``--foxglove PORT`` (the default, on 8765, when neither is given): open Foxglove (the desktop
app, or app.foxglove.dev), Open connection -> Foxglove WebSocket, ``ws://127.0.0.1:PORT``: the
recording plays at its own pace from the first client's subscription (play, pause, seek and
speed from the app's playback bar), with the body as a 3D scene entity (inertia box, omega and
L arrows) on ``/rigid_rot_sim/body_scene``. Needs foxglove-sdk (``pip install rigid_rot_sim[viewer]``).
Both at once serve both. Ctrl-C stops serving; ``make setup`` installs both extras.
"""

from __future__ import annotations

import threading


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "view",
        help="show a recording in a browser (--web) or Foxglove (no ROS)",
        description=__doc__.split("\n\n")[0],
    )
    parser.add_argument("bag", metavar="BAG.mcap")
    parser.add_argument(
        "--web",
        metavar="[HOST:]PORT",
        help="serve the body's web page here (host default 127.0.0.1; 0: any free port); needs viser",
    )
    parser.add_argument(
        "--foxglove",
        metavar="[HOST:]PORT",
        help="serve to Foxglove here (default, without --web: 8765 on 127.0.0.1; 0: any free port)",
    )
    parser.add_argument("--speed", type=float, default=1.0, help="initial playback speed (default 1)")
    parser.add_argument("--once", action="store_true", help="exit when the end is reached (default: serve on)")
    parser.set_defaults(handler=run)


def run(args) -> int:
    import signal

    from rigid_rot_sim.viewer import foxglove, web

    if not args.speed > 0.0:
        raise ValueError(f"--speed must be > 0, got {args.speed}")
    foxglove_address = args.foxglove if args.foxglove is not None or args.web is not None else "8765"
    players: list = []
    if args.web is not None:
        host, port = foxglove.parse_address(args.web, what="web page")
        if not web.available():
            raise ValueError("viser is not installed (pip install rigid_rot_sim[web])")
    if foxglove_address is not None:
        fox_host, fox_port = foxglove.parse_address(foxglove_address)
        if not foxglove.available():
            raise ValueError("foxglove-sdk is not installed (pip install rigid_rot_sim[viewer])")
    try:
        if foxglove_address is not None:
            from rigid_rot_sim.viewer.playback import RecordingPlayer

            try:
                player = RecordingPlayer(args.bag, fox_host, fox_port, speed=args.speed)
            except RuntimeError as exc:  # foxglove-sdk: the port is taken
                raise ValueError(f"cannot serve on {foxglove_address}: {exc}") from None
            players.append(player)
            print(f"serving {args.bag} to Foxglove at ws://{fox_host}:{player.port} (Ctrl-C stops)", flush=True)
        if args.web is not None:
            from rigid_rot_sim.viewer.web_playback import WebRecordingPlayer

            try:
                page = WebRecordingPlayer(args.bag, host, port, speed=args.speed)
            except OSError as exc:
                raise ValueError(f"cannot serve on {args.web}: {exc}") from None
            players.append(page)
            print(f"serving {args.bag} as a web page at http://{host}:{page.port}/ (Ctrl-C stops)", flush=True)
        for signum in (signal.SIGINT, signal.SIGTERM):
            signal.signal(signum, lambda *_: [each.stop() for each in players])
        threads = [threading.Thread(target=each.play, kwargs={"once": args.once}) for each in players[1:]]
        for thread in threads:
            thread.start()
        players[0].play(once=args.once)
        for thread in threads:  # with --once each ends by itself; Ctrl-C stops them all
            while thread.is_alive():
                thread.join(0.1)
    finally:
        for each in players:
            each.stop()
            each.close()
    return 0

"""The node's process: ``rclpy.init``, the run until it finishes, and ``main`` (the console script).

:func:`run_until_finished` is the one loop that runs a :class:`~rigid_rot_sim.ros.node.RigidRotSimNode`
(any :class:`SimulationNode`), for :func:`main` (``rigid_rot_sim.ros.node.main``: ``rigid_rot_sim_node``,
``python -m rigid_rot_sim.ros.node``) and for ``rigid-rot run``:
the run loop (:mod:`.run_loop`) on the main thread, the services, parameters and actions on an executor
thread, SIGINT / SIGTERM honoured at once, the nodes closed here (the recording's file complete).
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from collections.abc import Callable
from typing import Any, Protocol, cast

import rclpy
from rclpy.exceptions import NameValidationException, ParameterException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

from rigid_rot_sim.core import limits
from rigid_rot_sim.ros.run_loop import POLL_WALL
from rigid_rot_sim.share import ensure_ament_prefix_path

#: The node's name (``rigid_rot_sim``), also in its start-up errors.
NODE_NAME = "rigid_rot_sim"


class SimulationNode(Protocol):
    """What :func:`run_until_finished` runs (:class:`~rigid_rot_sim.ros.node.RigidRotSimNode`)."""

    @property
    def finished(self) -> bool: ...

    def detach_run_loop(self) -> None: ...

    def spin_run(self, keep_going: Callable[[], bool]) -> None: ...

    def flush_publishers(self, timeout: float = 1.0) -> None: ...


#: Most wall time (s) to wait at shutdown for a service in flight (a ~/step request is at most 0.25 s).
EXECUTOR_SHUTDOWN_WAIT = 2.0

#: What a bad scene, parameter or name raises while the node starts: exit code 2, one line.
STARTUP_ERRORS = (ValueError, ParameterException, NameValidationException)


def startup_error_line(exc: BaseException) -> str:
    """The one line (at most ``limits.MAX_ERROR_CHARS``) that reports a start-up error."""
    return limits.one_line(f"{NODE_NAME}: error: {exc}")


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt


def init_ros(args: list[str] | None) -> None:
    """``rclpy.init`` without rclpy's signal handlers: while nodes start, Ctrl-C / SIGTERM stop them at once.

    RuntimeError (rclpy's RCLError) for ROS arguments rcl cannot parse.
    """
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, _interrupt)


def run_until_finished(start: Callable[[list[Node]], SimulationNode], drain: float = 0.0) -> None:
    """Start the nodes and run them until the run finishes, Ctrl-C, SIGTERM or shutdown.

    ``start`` creates the nodes, adding each to the list it is given as soon as it exists,
    and returns the simulation node. The run loop (:mod:`.run_loop`) runs on this thread;
    an executor on a thread of its own serves every node's services, parameters and actions
    (and the other nodes' callbacks). Once they are started, SIGINT and SIGTERM only ask the
    loop to stop: the nodes (and the recording) then close here, never interrupted in a
    callback or a file write. When the run reached its duration, reliable subscribers get
    what was published (at most 1 s per publisher) and the executor serves ``drain`` s more
    for them. Then the executor's thread ends, every node is destroyed (last started first)
    and rclpy shut down: nothing of rclpy runs while the nodes are destroyed, so nothing is
    left to fail on a destroyed entity. A start-up error (:data:`STARTUP_ERRORS`) is raised
    after that.
    """
    nodes: list[Node] = []
    stop = threading.Event()
    executor: SingleThreadedExecutor | None = None
    server: threading.Thread | None = None
    try:
        node = start(nodes)
        for signum in (signal.SIGINT, signal.SIGTERM):
            signal.signal(signum, lambda *_: stop.set())
        node.detach_run_loop()  # the turns run on this thread, never on the executor's
        executor = SingleThreadedExecutor()
        for each in nodes:
            executor.add_node(each)
        server = threading.Thread(target=_serve, args=(executor, stop), name="rigid_rot_sim services", daemon=True)
        server.start()
        node.spin_run(lambda: rclpy.ok() and not stop.is_set())
        if node.finished and not stop.is_set():
            node.flush_publishers()
            stop.wait(drain)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        stop.set()
        if server is not None:
            server.join(EXECUTOR_SHUTDOWN_WAIT)  # a service in flight ends before the recording closes
        if executor is not None:
            executor.shutdown(timeout_sec=0)
        for each in reversed(nodes):
            each.destroy_node()
        rclpy.try_shutdown()


def _serve(executor: SingleThreadedExecutor, stop: threading.Event) -> None:
    """The services' thread: spin until asked to stop (each wait at most ``POLL_WALL``)."""
    try:
        while not stop.is_set() and executor.context.ok():
            executor.spin_once(timeout_sec=POLL_WALL)
    except ExternalShutdownException:
        pass


#: A diagnostic, off unless set: a directory where the node dumps tracemalloc snapshots (:func:`trace_memory`).
TRACE_MEMORY_ENV = "RIGID_ROT_TRACEMALLOC"


def trace_memory(directory: str) -> None:
    """Trace Python's allocations (tracemalloc, 8 frames) and dump a snapshot into ``directory`` on SIGUSR1
    and at exit (``snapshot_<n>.tracemalloc``, renamed into place once whole): what grew between two of them
    is what benchmarks/firehose_memory.py prints. Off by default; tracing slows the node down."""
    import atexit
    import itertools
    import tracemalloc

    tracemalloc.start(8)
    numbers = itertools.count(1)

    def dump(*_: object) -> None:
        path = os.path.join(directory, f"snapshot_{next(numbers)}.tracemalloc")
        tracemalloc.take_snapshot().dump(path + ".part")
        os.replace(path + ".part", path)

    signal.signal(signal.SIGUSR1, dump)
    atexit.register(dump)


def run_process(new_node: Callable[[], SimulationNode], args: list[str] | None = None) -> int:
    """:func:`init_ros` and :func:`run_until_finished` of the node ``new_node()`` makes, for a console script:
    exit code 0; a bad scene, parameter or ROS argument: one line on stderr, exit code 2."""

    def start_node(nodes: list[Node]) -> SimulationNode:
        node = new_node()
        nodes.append(cast(Node, node))  # RigidRotSimNode: a Node and a SimulationNode
        return node

    ensure_ament_prefix_path()  # the console script works without activating the venv
    if os.environ.get(TRACE_MEMORY_ENV):
        trace_memory(os.environ[TRACE_MEMORY_ENV])
    try:
        init_ros(args)
    except RuntimeError as exc:  # rclpy's RCLError: e.g. an unparsable --ros-args rule
        print(startup_error_line(RuntimeError(f"bad ROS arguments: {exc}")), file=sys.stderr, flush=True)
        return 2
    try:
        run_until_finished(start_node)
    except STARTUP_ERRORS as exc:  # SceneError, a scene the integrator cannot run, a bad parameter
        print(startup_error_line(exc), file=sys.stderr, flush=True)
        return 2
    return 0

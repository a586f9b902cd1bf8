"""Fixtures for end-to-end tests: the node in a subprocess, the test process as a DDS peer.

Isolation: test/conftest.py picks one ROS_DOMAIN_ID for the whole pytest session and sets it,
with ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, in ``os.environ`` at import time, so both the
test process and every subprocess see them. ROS log files go to a session temp directory.

Fixtures
--------
``ros_env``            dict: the environment for subprocesses (os.environ plus the above).
``launch_node``        factory: ``launch_node(*ros_args, name=...) -> NodeProcess``; the node
                       runs as ``python -m rigid_rot_sim.ros.node``; stopped after the test.
``launch_node_module`` the same factory, but its nodes live until the module's tests end.
``ros_node``           an rclpy node in a private Context of the test process.
``ros_node_module``    the same, shared by the tests of one module.

Helper fixtures (each returns a function; pass a NodeProcess to fail fast, with its log, when
the node dies while waiting):
``wait_for_service(client, timeout=30, process=None)``
``wait_for_topic(node, name, timeout=30, process=None) -> [type names]``
``call_service(node, client, request, timeout=10) -> response``
``collector``          a :class:`Collector` on ``ros_node``: subscribe, spin until a condition, call.

Plain helpers (no fixtures) are in ``e2e_helpers.py`` beside this file.

The ROS wheels' bootstrapper re-executes every venv Python once at start-up (``os.execve``,
same pid) unless ``_ROS_WHEELS_BOOTSTRAP_COMPLETE`` is set. Subprocesses here inherit the
test process's environment, which already has it, so they start once; signals reach the
right process either way because execve keeps the pid.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import pytest

# test/conftest.py set the session's domain and discovery range before this file loads.
ROS_DOMAIN_ID = int(os.environ["ROS_DOMAIN_ID"])

NODE = "/rigid_rot_sim"  # the node's default fully qualified name
NODE_START_TIMEOUT = 30.0  # s; a cold start on a loaded 2-core machine takes a few seconds
STOP_TIMEOUT = 10.0  # s to wait after SIGINT before SIGKILL


@dataclass
class NodeProcess:
    """A node running in a subprocess, its stdout+stderr in ``log_path``."""

    process: subprocess.Popen
    log_path: Path
    command: list[str] = field(default_factory=list)

    @property
    def pid(self) -> int:
        return self.process.pid

    def alive(self) -> bool:
        return self.process.poll() is None

    def log(self) -> str:
        return self.log_path.read_text(errors="replace") if self.log_path.exists() else ""

    def check_alive(self) -> None:
        """AssertionError with the node's log if the process has exited."""
        if not self.alive():
            raise AssertionError(
                f"node exited with code {self.process.returncode}: {' '.join(self.command)}\n"
                f"--- node log ---\n{self.log()}"
            )

    def stop(self, timeout: float = STOP_TIMEOUT) -> int:
        """SIGINT (a clean rclpy shutdown), then SIGKILL after ``timeout`` s; the exit code."""
        if self.alive():
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(timeout=timeout)
        return self.process.returncode


class _Launcher:
    def __init__(self, log_dir: Path, env: dict[str, str]) -> None:
        self.log_dir = log_dir
        self.env = env
        self.processes: list[NodeProcess] = []

    def __call__(
        self, *args: str, name: str = "node", module: str = "rigid_rot_sim.ros.node", env: dict[str, str] | None = None
    ) -> NodeProcess:
        """Start ``python -m <module> <args>`` (e.g. ``"--ros-args", "-p", "x:=1"``)."""
        log_path = self.log_dir / f"{name}-{len(self.processes)}.log"
        command = [sys.executable, "-m", module, *args]
        with open(log_path, "wb") as log:
            process = subprocess.Popen(
                command,
                stdout=log,
                stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL,
                env={**self.env, **(env or {})},
            )
        node = NodeProcess(process, log_path, command)
        self.processes.append(node)
        return node

    def stop_all(self) -> None:
        for node in self.processes:
            node.stop()
            # shown by pytest only when the test failed (captured output)
            print(f"--- log of {' '.join(node.command)} (exit code {node.process.returncode}) ---")
            print(node.log())


@pytest.fixture(scope="session")
def ros_env() -> dict[str, str]:
    return dict(os.environ)


@pytest.fixture
def launch_node(tmp_path, ros_env):
    launcher = _Launcher(tmp_path, ros_env)
    yield launcher
    launcher.stop_all()


@pytest.fixture(scope="module")
def launch_node_module(tmp_path_factory, ros_env):
    launcher = _Launcher(tmp_path_factory.mktemp("nodes"), ros_env)
    yield launcher
    launcher.stop_all()


@contextmanager
def _private_ros_node(name: str):
    import rclpy

    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node(name, context=context)
    try:
        yield node
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)


@pytest.fixture
def ros_node():
    """An rclpy node of the test process, in its own Context (independent of rclpy.init())."""
    with _private_ros_node(f"e2e_test_{os.getpid()}") as node:
        yield node


@pytest.fixture(scope="module")
def ros_node_module():
    """Like ``ros_node`` but shared by a module's tests (DDS discovery is paid once)."""
    with _private_ros_node(f"e2e_test_module_{os.getpid()}") as node:
        yield node


def _wait_for_service(client, timeout: float = NODE_START_TIMEOUT, process: NodeProcess | None = None) -> None:
    """Wait until ``client``'s service is discovered; fail fast if ``process`` dies."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if process is not None:
            process.check_alive()
        if client.wait_for_service(timeout_sec=0.2):
            return
    raise AssertionError(
        f"service {client.srv_name} not available within {timeout} s"
        + (f"\n--- node log ---\n{process.log()}" if process is not None else "")
    )


def _wait_for_topic(
    node, name: str, timeout: float = NODE_START_TIMEOUT, process: NodeProcess | None = None
) -> list[str]:
    """Wait until a publisher of topic ``name`` is discovered; its type names."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if process is not None:
            process.check_alive()
        if node.count_publishers(name) > 0:
            return dict(node.get_topic_names_and_types()).get(name, [])
        time.sleep(0.05)  # the graph is updated by DDS discovery threads; nothing to spin
    raise AssertionError(
        f"no publisher on {name} within {timeout} s"
        + (f"\n--- node log ---\n{process.log()}" if process is not None else "")
    )


def _call_service(node, client, request, timeout: float = 10.0):
    """Call a service from the test process and return the response (AssertionError on timeout)."""
    from rclpy.executors import SingleThreadedExecutor

    executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    try:
        future = client.call_async(request)
        executor.spin_until_future_complete(future, timeout_sec=timeout)
        if not future.done():
            raise AssertionError(f"no answer from {client.srv_name} within {timeout} s")
        return future.result()
    finally:
        executor.remove_node(node)
        executor.shutdown()


@pytest.fixture(scope="session")
def wait_for_service():
    return _wait_for_service


@pytest.fixture(scope="session")
def wait_for_topic():
    return _wait_for_topic


@pytest.fixture(scope="session")
def call_service():
    return _call_service


#: Seconds between two sends of an idempotent request that got no reply (Collector.call).
RESEND_PERIOD = 5.0


class Collector:
    """Subscribes in the test's rclpy node and spins until a condition holds."""

    def __init__(self, ros_node):
        from rclpy.executors import SingleThreadedExecutor

        self.node = ros_node
        self.executor = SingleThreadedExecutor(context=ros_node.context)
        self.executor.add_node(ros_node)
        self.messages: dict[str, list] = {}

    def subscribe(self, msg_type, topic: str, qos):
        self.messages[topic] = []
        self.node.create_subscription(msg_type, topic, self.messages[topic].append, qos)
        return self.messages[topic]

    def spin_until(self, condition, timeout: float, process=None, what: str = "condition"):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if condition():
                return
            if process is not None:
                process.check_alive()
            self.executor.spin_once(timeout_sec=0.05)
        raise AssertionError(
            f"timed out after {timeout} s waiting for {what}" + (f"\n{process.log()}" if process else "")
        )

    def call(self, srv_type, name: str, request, timeout: float = 10.0, process=None, idempotent: bool = False):
        """Call service ``name`` (relative: of the default node ``/rigid_rot_sim``) and return the reply.

        ``idempotent``: send the request again every ``RESEND_PERIOD`` s until a reply comes. A
        fresh server's Fast DDS drops its reply when it has not yet matched the client's reply
        reader within 100 ms ("failed to send response (timeout)", ros2/rmw_fastrtps#704);
        ``service_is_ready`` only says that the request reached it.
        """
        client = self.node.create_client(srv_type, name if name.startswith("/") else f"{NODE}/{name}")
        self.spin_until(lambda: client.service_is_ready(), 2 * NODE_START_TIMEOUT, process, f"service {name}")
        futures = [client.call_async(request)]
        now = time.monotonic()
        deadline, resend = now + max(timeout, 30.0), now + RESEND_PERIOD
        while not any(f.done() for f in futures):
            now = time.monotonic()
            if now > deadline:
                raise AssertionError(
                    f"timed out waiting for reply of {name}" + (f"\n{process.log()}" if process else "")
                )
            if idempotent and now > resend:
                futures.append(client.call_async(request))
                resend = now + RESEND_PERIOD
            if process is not None:
                process.check_alive()
            self.executor.spin_once(timeout_sec=0.05)
        return next(f for f in futures if f.done()).result()

    def close(self):
        self.executor.remove_node(self.node)
        self.executor.shutdown()


@pytest.fixture
def collector(ros_node):
    c = Collector(ros_node)
    yield c
    c.close()

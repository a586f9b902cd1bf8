"""End to end: the node records its run to MCAP while torque commands arrive over DDS.

The recorded file is read with independent readers (rosbags, the mcap library), survives
SIGINT / SIGTERM / SIGKILL as documented, re-simulates bit for bit, and its torque
commands replayed into a fresh node reproduce the original states.

Robust on a loaded machine: what a test counts comes from the recording (every published
message and every command the node received is in it), and a test that needs the node to have
received something waits until the file (read while it is written) shows it.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import yaml
from e2e_helpers import WAIT, recorded_count, wait_until_recorded  # beside this file

from rigid_rot_sim.message_fields import time_to_seconds
from rigid_rot_sim.recording.events import decode_event
from rigid_rot_sim.recording.reader import BagReader, repair
from rigid_rot_sim.recording.resim import resimulate

REPO = Path(__file__).resolve().parents[2]
TORQUE_TOPIC = "/rigid_rot_sim/torque"
STATE_TOPIC = "/rigid_rot_sim/state"


def write_scene(directory: Path, real_time_factor: float = 1.0, hold: object = "hold") -> Path:
    """A torque-driven scene (rk4, 1 kHz, commands in the header's frame)."""
    scene = yaml.safe_load((REPO / "config" / "scenes" / "torque_driven.yaml").read_text())
    scene["integrator"] = {"method": "rk4", "dt": 0.001}
    scene["real_time_factor"] = real_time_factor
    scene["torque_inputs"][0]["hold"] = hold
    scene["outputs"] = {
        "state": 50,
        "orientation": 50,
        "angular_velocity": 0,
        "angular_momentum": 0,
        "tf": 25,
        "clock": 50,
    }
    path = directory / "scene.yaml"
    path.write_text(yaml.safe_dump(scene, sort_keys=False))
    return path


def node_args(scene: Path, record: Path, *extra: str) -> list[str]:
    return ["--ros-args", "-p", f"scene:={scene}", "-p", f"record_path:={record}", *extra]


def first_state_time(ros_node, process, timeout: float = WAIT) -> float:
    """Sim time (s) of the first ~/state message the test process receives."""
    from rclpy.executors import SingleThreadedExecutor

    from rigid_rot_msgs.msg import RigidBodyState

    got: list[float] = []
    subscription = ros_node.create_subscription(
        RigidBodyState, STATE_TOPIC, lambda m: got.append(m.header.stamp.sec + m.header.stamp.nanosec * 1e-9), 10
    )
    executor = SingleThreadedExecutor(context=ros_node.context)
    executor.add_node(ros_node)
    try:
        deadline = time.monotonic() + timeout
        while not got and time.monotonic() < deadline:
            process.check_alive()
            executor.spin_once(timeout_sec=0.1)
    finally:
        executor.remove_node(ros_node)
        executor.shutdown()
        ros_node.destroy_subscription(subscription)
    assert got, f"no state within {timeout} s\n{process.log()}"
    return got[0]


def send_commands(ros_node, commands, process, bag: Path) -> None:
    """Publish WrenchStamped commands [(torque, frame_id, stamp_s, force)] once a subscriber matches,
    and wait until the node has received (and recorded) every one."""
    from geometry_msgs.msg import WrenchStamped

    before = recorded_count(bag, TORQUE_TOPIC)
    publisher = ros_node.create_publisher(WrenchStamped, TORQUE_TOPIC, 10)
    deadline = time.monotonic() + WAIT
    while publisher.get_subscription_count() == 0:
        process.check_alive()
        assert time.monotonic() < deadline, "the node never subscribed to its torque topic"
        time.sleep(0.05)
    for torque, frame_id, stamp, force in commands:
        msg = WrenchStamped()
        msg.header.frame_id = frame_id
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(round(stamp * 1e9), 1_000_000_000)
        msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z = torque
        msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = force
        publisher.publish(msg)
        time.sleep(0.05)
    # reliable QoS, depth 10 >= the commands sent: each reaches the node; wait until it has taken them
    wait_until_recorded(bag, TORQUE_TOPIC, before + len(commands), process)
    ros_node.destroy_publisher(publisher)


COMMANDS = [
    ((0.0, 0.0, 0.004), "base_link", 0.0, (0.0, 0.0, 0.0)),
    ((0.002, 0.0, 0.0), "odom", 0.0, (0.0, 0.0, 0.0)),
    ((0.0, 0.001, 0.0), "no_such_frame", 0.0, (0.0, 0.0, 0.0)),  # rejected: unknown frame
    ((0.0, 0.0, 0.001), "base_link", 0.0, (1.0, 0.0, 0.0)),  # rejected: non-zero force
    ((float("nan"), 0.0, 0.0), "base_link", 0.0, (0.0, 0.0, 0.0)),  # rejected: non-finite
    ((0.0, -0.003, 0.001), "base_link", 0.0, (0.0, 0.0, 0.0)),
]


@pytest.fixture(scope="module")
def recorded_run(tmp_path_factory, launch_node_module, ros_node_module):
    """One recorded run with accepted and rejected commands, stopped with SIGINT."""
    directory = tmp_path_factory.mktemp("run")
    bag = directory / "run.mcap"
    node = launch_node_module(*node_args(write_scene(directory), bag), name="recorder")
    first_state_time(ros_node_module, node)
    send_commands(ros_node_module, COMMANDS, node, bag)
    assert node.stop() == 0, node.log()
    return bag, node


def test_rosbags_deserialises_every_message_and_counts_match(recorded_run):
    from rosbags.highlevel import AnyReader

    bag, _ = recorded_run
    counts: dict[str, int] = {}
    with AnyReader([bag]) as reader:
        for connection, _, raw in reader.messages():
            reader.deserialize(raw, connection.msgtype)
            counts[connection.topic] = counts.get(connection.topic, 0) + 1
        summary_counts = {c.topic: c.msgcount for c in reader.connections}
        types = {c.topic: c.msgtype for c in reader.connections}
    assert {t: n for t, n in summary_counts.items() if n} == counts
    assert counts[TORQUE_TOPIC] == len(COMMANDS)  # every command, as received
    assert counts["/rigid_rot_sim/rejected"] == 3  # with the reason of each rejection
    assert counts["/rigid_rot_sim/sim_events"] == 3  # the accepted ones, with effective times
    assert counts[STATE_TOPIC] > 10 and counts["/tf"] > 5 and counts["/rigid_rot_sim/mass_properties"] == 1
    assert types["/tf"] == "tf2_msgs/msg/TFMessage"
    assert types["/rigid_rot_sim/rejected"] == "rigid_rot_msgs/msg/RejectedCommand"


def test_commands_keep_receive_time_and_header_and_rejections_say_why(recorded_run):
    bag, _ = recorded_run
    reader = BagReader(bag)
    commands = [(m, msg) for m, msg in reader.decoded([TORQUE_TOPIC])]
    assert [msg.header.frame_id for _, msg in commands] == [c[1] for c in COMMANDS]
    # log time = the sim time at receipt (time base "sim"), which the accepted ones' events also hold
    events = [decode_event(msg) for _, msg in reader.decoded(["/rigid_rot_sim/sim_events"])]
    receipts = [round(e.number("receipt_time") * 1e9) for e in events if e.kind == "torque"]
    assert len(receipts) == 3 and set(receipts) <= {m.log_time_ns for m, _ in commands}
    assert all(0 <= m.log_time_ns < 1e15 for m, _ in commands)  # sim time, not ns since the epoch
    assert reader.metadata["log_time"] == {"base": "sim"}
    reasons = [msg.reason for _, msg in reader.decoded(["/rigid_rot_sim/rejected"])]
    assert "no_such_frame" in reasons[0] and "force" in reasons[1] and "non-finite" in reasons[2]


def test_summary_statistics_and_channel_metadata(recorded_run):
    from mcap.reader import make_reader

    bag, _ = recorded_run
    with open(bag, "rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert reader.get_header().profile == "ros2"
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
    assert summary.statistics.message_count == sum(summary.statistics.channel_message_counts.values()) > 0
    assert summary.chunk_indexes and all(ci.message_index_offsets for ci in summary.chunk_indexes)
    for channel in summary.channels.values():
        assert channel.message_encoding == "cdr"
        assert yaml.safe_load(channel.metadata["offered_qos_profiles"])[0]["reliability"] == 1
        assert channel.metadata["topic_type_hash"].startswith("RIHS01_")
    assert {"rosbag2", "scene", "parameters", "integrator", "versions"} <= set(metadata)
    assert yaml.safe_load(metadata["scene"]["text"])["integrator"]["method"] == "rk4"
    assert metadata["integrator"]["method"] == "rk4"
    assert yaml.safe_load(metadata["rosbag2"]["serialized_metadata"])["version"] == 8


def test_resim_is_bit_exact_with_the_same_integrator_and_differs_with_another(recorded_run):
    bag, _ = recorded_run
    same = resimulate(bag)
    assert same.identical and same.states > 10 and same.events == 3, same.format()
    other = resimulate(bag, method="lie_rk4")
    assert not other.identical and other.max_attitude_error > 0.0, other.format()


def test_sigterm_finishes_the_file(tmp_path, launch_node, ros_node):
    bag = tmp_path / "term.mcap"
    node = launch_node(*node_args(write_scene(tmp_path), bag), name="term")
    first_state_time(ros_node, node)
    node.process.send_signal(signal.SIGTERM)
    assert node.process.wait(timeout=20) == 0, node.log()
    reader = BagReader(bag)
    assert reader.complete and reader.counts()[STATE_TOPIC] > 0


def test_sigkill_loses_at_most_the_last_second_and_repair_recovers_it(tmp_path, launch_node, ros_node):
    bag = tmp_path / "killed.mcap"
    # wall-clock log times (the option), so that the loss is measured against the wall clock
    node = launch_node(*node_args(write_scene(tmp_path), bag, "-p", "record_log_time:=wall"), name="killed")
    first_state_time(ros_node, node)
    wait_until_recorded(bag, STATE_TOPIC, 25, node)  # more than 20 flushed to the file
    killed_at = time.time_ns()
    node.process.kill()
    node.process.wait(timeout=10)
    reader = BagReader(bag)
    assert not reader.complete
    states = [m for m in reader.messages([STATE_TOPIC])]
    assert len(states) > 20 and states[0].log_time_ns > 1.6e18  # ns since the epoch
    assert (killed_at - states[-1].log_time_ns) / 1e9 < 1.0  # flushed every 0.5 s: at most the last second lost
    report = repair(bag)
    assert report.messages == sum(reader.counts().values())
    repaired = BagReader(bag)
    assert repaired.complete
    assert resimulate(bag).identical  # the recovered part is still a faithful record


def set_paused(ros_node, process, paused: bool, wait_for_service, call_service) -> float:
    """Call ~/pause; the sim time (s) the node reports it paused or resumed at."""
    from std_srvs.srv import SetBool

    client = ros_node.create_client(SetBool, "/rigid_rot_sim/pause")
    try:
        wait_for_service(client, process=process)
        response = call_service(ros_node, client, SetBool.Request(data=paused))
    finally:
        ros_node.destroy_client(client)
    assert response.success, response.message
    return float(response.message.rsplit("t = ", 1)[1].split()[0])


def reset(ros_node, process, wait_for_service, call_service) -> None:
    from std_srvs.srv import Trigger

    client = ros_node.create_client(Trigger, "/rigid_rot_sim/reset")
    try:
        wait_for_service(client, process=process)
        response = call_service(ros_node, client, Trigger.Request())
    finally:
        ros_node.destroy_client(client)
    assert response.success, response.message


def wait_for_sim_time(ros_node, process, t: float, timeout: float = 60.0) -> None:
    """Spin until a ~/state stamped at or after t (s) arrives."""
    from rclpy.executors import SingleThreadedExecutor

    from rigid_rot_msgs.msg import RigidBodyState

    latest = [-1.0]
    subscription = ros_node.create_subscription(
        RigidBodyState,
        STATE_TOPIC,
        lambda m: latest.__setitem__(0, max(latest[0], m.header.stamp.sec + m.header.stamp.nanosec * 1e-9)),
        10,
    )
    executor = SingleThreadedExecutor(context=ros_node.context)
    executor.add_node(ros_node)
    try:
        deadline = time.monotonic() + timeout
        while latest[0] < t:
            process.check_alive()
            assert time.monotonic() < deadline, f"sim time {t} s not reached (latest state {latest[0]} s)"
            executor.spin_once(timeout_sec=0.1)
    finally:
        executor.remove_node(ros_node)
        executor.shutdown()
        ros_node.destroy_subscription(subscription)


def test_replayed_commands_reproduce_the_states_of_the_original_run(
    tmp_path, launch_node, ros_node, wait_for_service, call_service
):
    # Commands stamped in the future take effect at their stamp (sim time), not when they
    # arrive: replayed into a fresh node they must give the same states, bit for bit. Each
    # node is paused while commands reach it, so a slow machine cannot move its sim time past
    # the stamps; pausing changes nothing in the physics.
    scene = write_scene(tmp_path)
    original, replayed = tmp_path / "original.mcap", tmp_path / "replayed.mcap"

    node = launch_node(*node_args(scene, original), name="original")
    first_state_time(ros_node, node)
    t_pause = set_paused(ros_node, node, True, wait_for_service, call_service)
    stamps = tuple(round(t_pause + 1.0 + 0.4 * i, 1) for i in range(3))
    send_commands(
        ros_node,
        [
            ((0.0, 0.0, 0.004), "base_link", stamps[0], (0.0, 0.0, 0.0)),
            ((0.003, 0.0, 0.0), "odom", stamps[1], (0.0, 0.0, 0.0)),
            ((0.0, -0.002, 0.0), "base_link", stamps[2], (0.0, 0.0, 0.0)),
        ],
        node,
        original,
    )
    set_paused(ros_node, node, False, wait_for_service, call_service)
    end = stamps[-1] + 0.6
    wait_for_sim_time(ros_node, node, end)
    assert node.stop() == 0, node.log()

    node = launch_node(*node_args(scene, replayed), name="replayed")
    first_state_time(ros_node, node)
    set_paused(ros_node, node, True, wait_for_service, call_service)
    reset(ros_node, node, wait_for_service, call_service)  # back to t = 0, still paused
    rigid_rot = Path(sys.executable).with_name("rigid-rot")
    done = subprocess.run(
        [str(rigid_rot), "replay", str(original), "--wait", "20"],
        capture_output=True,
        text=True,
        timeout=120,
        env=os.environ,
    )
    assert done.returncode == 0 and "replayed 3 messages" in done.stdout, done.stdout + done.stderr
    deadline = time.monotonic() + WAIT
    while len(_events(replayed, complete=False)) < 4:  # reset + 3 commands, received before resuming
        node.check_alive()
        assert time.monotonic() < deadline, f"events recorded: {_events(replayed, complete=False)}\n{node.log()}"
        time.sleep(0.2)
    set_paused(ros_node, node, False, wait_for_service, call_service)
    wait_for_sim_time(ros_node, node, end)
    assert node.stop() == 0, node.log()

    def command_events(bag):
        return [(e.values["effective_time"], e.values["receipt_time"]) for e in _events(bag) if e.kind == "torque"]

    # both took effect at the stamps (as the headers carry them: whole ns), having arrived before them
    in_headers = [
        time_to_seconds(SimpleNamespace(sec=sec, nanosec=ns))
        for sec, ns in (divmod(round(stamp * 1e9), 1_000_000_000) for stamp in stamps)
    ]
    assert [float(e) for e, _ in command_events(original)] == in_headers, command_events(original)
    assert [float(e) for e, _ in command_events(replayed)] == in_headers, command_events(replayed)
    a, b = _states_by_stamp(original), _states_by_stamp(replayed, after_reset=True)
    common = sorted(s for s in set(a) & set(b) if s <= end)
    assert len(common) > 50 and common[-1] >= stamps[-1] + 0.5
    differing = [stamp for stamp in common if a[stamp] != b[stamp]]
    assert not differing, f"states differ at {len(differing)} of {len(common)} stamps, first at t = {differing[0]}"
    moved = [s for s in common if s > stamps[2]]
    assert np.linalg.norm(a[moved[-1]][1]) > 0.01  # the commands did change ω
    assert resimulate(replayed).identical  # reset and all: the replayed run re-simulates exactly


def _events(bag, complete=True):
    """The recorded simulation events; ``complete=False`` also reads a file still being written."""
    from rigid_rot_sim.recording.events import decode_event

    reader = BagReader(bag)
    assert reader.complete or not complete
    return [decode_event(msg) for _, msg in reader.decoded(["/rigid_rot_sim/sim_events"])]


def _states_by_stamp(bag, after_reset=False):
    """{sim time: (q, ω, T)} of the recorded states (only those after the last reset, if asked)."""
    reader = BagReader(bag)
    states = {}
    for record, msg in reader.decoded([STATE_TOPIC, "/rigid_rot_sim/sim_events"]):
        if record.topic != STATE_TOPIC:
            if after_reset and msg.name.endswith("/reset"):
                states.clear()  # log order is the order the node produced them in
            continue
        t = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        q, w = msg.orientation, msg.angular_velocity_body
        states[round(t, 6)] = ((q.x, q.y, q.z, q.w), (w.x, w.y, w.z), msg.kinetic_energy)
    return states


def test_rigid_rot_run_record_writes_a_complete_bag_with_sim_time_log_times(tmp_path):
    """An rtf-0 run: complete, log times equal to the sim times (the default base: every stamp and
    /clock equals its log time, so playback paced by log time, as ros2 bag play and Foxglove do,
    runs at sim pace), and resim bit-exact."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    bag = tmp_path / "cli.mcap"
    rigid_rot = Path(sys.executable).with_name("rigid-rot")
    done = subprocess.run(
        [
            str(rigid_rot),
            "run",
            str(write_scene(tmp_path)),
            "--duration",
            "0.5",
            "--realtime-factor",
            "0",
            "--record",
            str(bag),
        ],
        capture_output=True,
        text=True,
        timeout=60,
        env=os.environ,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    reader = BagReader(bag)
    assert reader.complete and reader.metadata["log_time"] == {"base": "sim"}
    stamps = {
        round(msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9, 6) for _, msg in reader.decoded([STATE_TOPIC])
    }
    assert stamps == {round(0.02 * i, 6) for i in range(26)}  # 50 Hz over 0.5 s, both ends included
    checked: dict[str, int] = {}
    log_times = []
    with open(bag, "rb") as stream:  # the mcap library's own reader, in log-time order
        for _, channel, message, decoded in make_reader(
            stream, decoder_factories=[DecoderFactory()]
        ).iter_decoded_messages():
            log_times.append(message.log_time)
            if channel.topic in (STATE_TOPIC, "/rigid_rot_sim/orientation"):
                stamp = decoded.header.stamp
            elif channel.topic == "/clock":
                stamp = decoded.clock
            elif channel.topic == "/tf":
                stamp = decoded.transforms[0].header.stamp
            else:
                continue
            assert message.log_time == stamp.sec * 1_000_000_000 + stamp.nanosec, (
                channel.topic,
                message.log_time,
                stamp,
            )
            checked[channel.topic] = checked.get(channel.topic, 0) + 1
    # /tf at 25 Hz: 13, plus the final state at 0.5 s (every output ends on it)
    assert checked[STATE_TOPIC] == 26 and checked["/clock"] == 26 and checked["/tf"] == 14
    assert log_times == sorted(log_times) and log_times[0] == 0 and log_times[-1] == 500_000_000
    assert resimulate(bag).identical


@pytest.mark.parametrize(
    "where, reason",
    [
        ("a_file/run.mcap", "File exists"),  # a file where a directory must be
        ("/proc/rigid_rot_no_such_dir/run.mcap", "No such file or directory"),  # cannot be created (issue 29)
        ("/dev/full", "No space left on device"),  # a full disk: the file opens, its first write fails (ENOSPC)
    ],
)
def test_a_recording_that_cannot_start_is_reported_and_the_simulation_runs_and_publishes(
    where, reason, tmp_path, launch_node, ros_node
):
    """Not just the t = 0 state published at start-up: the run goes on at its pace (sim time passes)."""
    (tmp_path / "a_file").write_text("not a directory")
    path = tmp_path / where  # an absolute ``where`` replaces tmp_path
    node = launch_node(*node_args(write_scene(tmp_path), path), name="unwritable")
    wait_for_sim_time(ros_node, node, 0.5)
    node.check_alive()
    log = node.log()
    assert f"cannot record to {path}: {reason}; the simulation runs without recording" in log, log
    assert "no recording (see the error above)" in log and "simulation paused" not in log
    assert node.stop() == 0, node.log()


def test_disk_full_mid_run_stops_the_recording_and_the_simulation_runs_on(tmp_path, ros_env, ros_node):
    import resource

    def limit_file_size() -> None:  # in the child: writes past 35 kB fail (EFBIG), like a full disk
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (35_000, 35_000))

    bag = tmp_path / "full.mcap"
    log_path = tmp_path / "full.log"
    with open(log_path, "wb") as log:
        process = subprocess.Popen(
            [sys.executable, "-m", "rigid_rot_sim.ros.node", *node_args(write_scene(tmp_path), bag)],
            stdout=log,
            stderr=subprocess.STDOUT,
            env=ros_env,
            preexec_fn=limit_file_size,
        )

    class Proc:  # what first_state_time needs of a NodeProcess
        def check_alive(self):
            assert process.poll() is None, log_path.read_text()

        def log(self):
            return log_path.read_text()

    try:
        first_state_time(ros_node, Proc())
        deadline = time.monotonic() + 30.0
        while "stopped after" not in log_path.read_text() and time.monotonic() < deadline:
            Proc().check_alive()
            time.sleep(0.1)
        text = log_path.read_text()
        assert f"recording to {bag} stopped after" in text and "File too large" in text
        assert "the simulation continues without recording" in text
        later = first_state_time(ros_node, Proc())  # still simulating and publishing
        assert later > 1.0
    finally:
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=20) == 0, log_path.read_text()
    assert len(BagReader(bag).counts()) > 0  # what was flushed before the error is readable


def test_replay_exits_2_with_the_nodes_reason_when_it_refuses_replayed_commands(recorded_run, tmp_path, launch_node):
    """The recorded run holds commands the node refused (an unknown frame, a force, NaN): replayed into a
    live node they are refused again, and rigid-rot replay says so (issue 29; it reported success)."""
    bag, _ = recorded_run
    node = launch_node("--ros-args", "-p", f"scene:={write_scene(tmp_path)}", name="replay_target")
    rigid_rot = Path(sys.executable).with_name("rigid-rot")
    done = subprocess.run(
        [str(rigid_rot), "replay", str(bag), "--wait", "60", "--rate", "5"],
        capture_output=True,
        text=True,
        timeout=180,
        env=os.environ,
    )
    assert done.returncode == 2 and done.stdout == "", done.stdout + done.stderr
    (line,) = done.stderr.strip().splitlines()
    assert line.startswith("rigid-rot replay: error: /rigid_rot_sim rejected "), line
    assert f"of the {len(COMMANDS)} replayed commands (first on {TORQUE_TOPIC}): " in line, line
    assert "'no_such_frame'" in line or "force" in line, line  # the node's reason for one of them
    node.check_alive()

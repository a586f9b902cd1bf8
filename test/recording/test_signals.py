"""A recording process stopped by SIGINT / SIGTERM leaves a complete file; after SIGKILL at
most the last second is missing, and repair restores the index."""

import os
import signal
import subprocess
import sys
import time

import pytest

from rigid_rot_sim.recording.reader import BagReader, repair

pytest.importorskip("rclpy")

RECORDING_SCRIPT = r"""
import signal, sys, time
from geometry_msgs.msg import Vector3Stamped
from rigid_rot_sim.recording.writer import Recorder

def terminate(signum, frame):
    raise SystemExit(0)            # unwinds through `with`: the file is finished

signal.signal(signal.SIGTERM, terminate)
written = 0
try:
    with Recorder(sys.argv[1], flush_period=0.5) as recorder:   # what the node uses
        recorder.add_topic("/counter", "geometry_msgs/msg/Vector3Stamped")
        msg = Vector3Stamped()
        while True:
            msg.vector.x = float(written)
            recorder.write_message("/counter", msg, time.time_ns())
            written += 1
            if written == 1:
                print("recording", flush=True)
            time.sleep(0.005)
except KeyboardInterrupt:
    pass
finally:
    print(f"written {written}", flush=True)
"""


def start_recording(path):
    process = subprocess.Popen(
        [sys.executable, "-c", RECORDING_SCRIPT, str(path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert process.stdout.readline().strip() == "recording", process.stderr.read()
    return process


def counters(path):
    reader = BagReader(path)
    return reader, [(m.vector.x, rec.log_time_ns) for rec, m in reader.decoded()]


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_sigint_and_sigterm_finish_the_file(tmp_path, sig):
    path = tmp_path / "run.mcap"
    process = start_recording(path)
    time.sleep(1.5)
    process.send_signal(sig)
    out, err = process.communicate(timeout=20)
    assert process.returncode == 0, err
    written = int(out.split("written")[1])
    reader, values = counters(path)
    assert reader.complete
    assert [v for v, _ in values] == [float(i) for i in range(written)]


def test_sigkill_loses_at_most_the_last_second_and_repair_recovers_the_rest(tmp_path):
    path = tmp_path / "run.mcap"
    process = start_recording(path)
    time.sleep(3.2)
    killed_at = time.time_ns()
    os.kill(process.pid, signal.SIGKILL)
    process.wait(timeout=10)
    reader, values = counters(path)
    assert not reader.complete
    got = [v for v, _ in values]
    assert got == [float(i) for i in range(len(got))]  # a gap-free prefix
    last_kept_ns = values[-1][1]
    # flushed every 0.5 s: everything logged more than a second before the kill is there
    assert (killed_at - last_kept_ns) / 1e9 < 1.0
    assert len(got) > 50  # ~3 s of messages at up to 200 per second
    report = repair(path)
    assert report.messages == len(got) and not report.already_complete
    repaired, values_after = counters(path)
    assert repaired.complete and [v for v, _ in values_after] == got

"""Helpers of the e2e tests that are plain functions (import them: ``from e2e_helpers import ...``)."""

from __future__ import annotations

import time

WAIT = 60.0  # s: generous; the condition ends a wait (a loaded 2-core machine is slow)


def recorded_count(bag, topic: str) -> int:
    """Messages of ``topic`` in a recording, also while it is being written (its flushed part)."""
    from rigid_rot_sim.recording.reader import BagReader

    try:
        return BagReader(bag).counts().get(topic, 0)
    except Exception:
        return 0


def wait_until_recorded(bag, topic: str, count: int, process, timeout: float = WAIT) -> None:
    """Wait until the node's recording holds ``count`` messages on ``topic`` (it flushes every 0.5 s):
    what the node has received (torque commands) or published, whatever reached this process."""
    deadline = time.monotonic() + timeout
    while recorded_count(bag, topic) < count:
        process.check_alive()
        assert time.monotonic() < deadline, (
            f"{topic}: {recorded_count(bag, topic)} of {count} recorded\n{process.log()}"
        )
        time.sleep(0.1)

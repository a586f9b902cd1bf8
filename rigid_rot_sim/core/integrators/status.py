"""What a fixed-step kernel returns with its new state (see ``fixed_step.py`` for the contract).

A kernel works on ``State = (qx, qy, qz, qw, w1, w2, w3)`` (principal frame, q principal ->
world) and reports :data:`OK` or the code of the failure it detected. The compiled loop
(``kernels.py``) adds :data:`NON_FINITE` for a step whose state is not finite.
"""

from __future__ import annotations

__all__ = ["State", "StepResult", "OK", "NON_FINITE", "NEWTON_FAILED", "KICK_FAILED"]

State = tuple[float, float, float, float, float, float, float]
#: What a kernel returns: the new state and a status code.
StepResult = tuple[State, int]

#: Kernel status codes.
OK, NON_FINITE, NEWTON_FAILED, KICK_FAILED = 0, 1, 2, 3

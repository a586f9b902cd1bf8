"""Plots of a validation: measured rate against both replays, and their residuals (PNG, matplotlib Agg)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from rigid_rot_sim.identify.data import Measurements
from rigid_rot_sim.identify.report import Validation


def plot_validation(measurements: Measurements, validation: Validation, out: str | os.PathLike[str]) -> list[Path]:
    """Write ``replay_rate.png`` and ``replay_residuals.png`` to ``out``; their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory = Path(out)
    directory.mkdir(parents=True, exist_ok=True)
    replays = [r for r in (validation.nominal, validation.identified) if r is not None]
    t = measurements.t
    paths = []
    fig, axes = plt.subplots(3, 1, sharex=True, figsize=(9, 7))
    for i, ax in enumerate(axes):
        ax.plot(t, measurements.omega[:, i], ".", ms=1.5, color="0.5", label="measured")
        for r in replays:
            ax.plot(t, r.omega[:, i], lw=1.0, label=f"{r.label} replay")
        ax.set_ylabel(f"omega_{'xyz'[i]} (rad/s)")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("t (s)")
    fig.suptitle("gyro: measured and replayed (body frame)")
    fig.tight_layout()
    paths.append(directory / "replay_rate.png")
    fig.savefig(paths[-1], dpi=100)
    plt.close(fig)
    fig, axes = plt.subplots(len(replays), 1, sharex=True, figsize=(9, 2.5 + 2.2 * len(replays)), squeeze=False)
    for ax, r in zip(axes[:, 0], replays, strict=True):
        residual = r.omega - measurements.omega
        for i in range(3):
            ax.plot(t, residual[:, i], lw=0.6, label="xyz"[i])
        ax.set_ylabel("rad/s")
        ax.set_title(f"{r.label}: replay - measured (RMS {r.omega_rms:.3g} rad/s)", fontsize=9)
        ax.legend(loc="upper right", fontsize=8)
        lim = np.max(np.abs(residual)) if residual.size else 1.0
        ax.set_ylim(-1.05 * lim, 1.05 * lim)
    axes[-1, 0].set_xlabel("t (s)")
    fig.tight_layout()
    paths.append(directory / "replay_residuals.png")
    fig.savefig(paths[-1], dpi=100)
    plt.close(fig)
    return paths

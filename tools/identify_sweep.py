"""The identifiability sweep of docs/identify.md: sigma of each principal moment against the data length.

    .venv/bin/python tools/identify_sweep.py [--out docs/identify_sweep.png]

For each shipped excitation profile (config/scenes/excitation*.yaml: its tensor, initial rate and
torque schedule) and gyro noise level (white, rad/s per reading at 100 Hz), the first L seconds are
simulated (the compiled RK4 of rigid_rot_sim.identify, 0.5 ms steps), read by a gyro with that noise
(seed 31) and identified; the plot shows the reported one-sigma of each principal moment relative
to the moment. The reported sigma is the Cramer-Rao bound of the fit, checked against the spread of
estimates over seeds in test/identify/test_identify.py. About 30 s.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import yaml

from rigid_rot_sim.identify import Measurements, PiecewiseTorque, identify
from rigid_rot_sim.identify.report import simulate_window

REPO = Path(__file__).resolve().parents[1]
PROFILES = ("excitation", "excitation_gentle")
NOISE = (1e-4, 1e-3, 1e-2)  # rad/s per reading
LENGTHS = (5.0, 10.0, 20.0, 40.0, 60.0)  # s
RATE = 100.0  # Hz


def profile(name: str) -> tuple[np.ndarray, np.ndarray, PiecewiseTorque]:
    scene = yaml.safe_load((REPO / "config" / "scenes" / f"{name}.yaml").read_text(encoding="utf-8"))
    segments = scene["torque_inputs"][0]["schedule"]["segments"]
    torque = PiecewiseTorque([s["start"] for s in segments], [s["torque"] for s in segments])
    return np.array(scene["body"]["inertia_tensor"]), np.array(scene["initial"]["angular_velocity"]), torque


def sweep() -> dict[tuple[str, float], np.ndarray]:
    """(profile, noise) -> (len(LENGTHS), 3) relative sigma of the principal moments."""
    out = {}
    for name in PROFILES:
        inertia, omega0, torque = profile(name)
        moments = np.linalg.eigvalsh(inertia)
        t = np.arange(int(max(LENGTHS) * RATE) + 1) / RATE
        clean = simulate_window(
            Measurements(t, np.zeros((t.size, 3)), torque), inertia, omega0, "truth", max_step=5e-4
        ).omega
        for noise in NOISE:
            rng = np.random.default_rng(31)
            readings = clean + noise * rng.standard_normal(clean.shape)
            rows = []
            for length in LENGTHS:
                keep = t <= length
                result = identify(Measurements(t[keep], readings[keep], torque))
                rows.append(result.principal_moments_sigma / moments)
                print(f"{name:18s} noise {noise:.0e} rad/s  {length:4.0f} s: sigma/moment "
                      + " ".join(f"{v:.1e}" for v in rows[-1]))  # fmt: skip
            out[(name, noise)] = np.array(rows)
    return out


def plot(results: dict[tuple[str, float], np.ndarray], path: Path) -> None:
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(PROFILES), figsize=(9, 3.6), sharey=True)
    colors = {noise: c for noise, c in zip(NOISE, ("tab:green", "tab:blue", "tab:red"), strict=True)}
    for ax, name in zip(axes, PROFILES, strict=True):
        for noise in NOISE:
            rel = results[(name, noise)]
            for axis, style in zip(range(3), ("-", "--", ":"), strict=True):
                label = f"{noise:.0e} rad/s" if axis == 0 else None
                ax.loglog(LENGTHS, rel[:, axis], style, color=colors[noise], marker="o", ms=3, label=label)
        ax.set_xticks(LENGTHS, [f"{v:g}" for v in LENGTHS])
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_title(name, fontsize=10)
        ax.set_xlabel("data length (s)")
        ax.grid(True, which="both", lw=0.3)
    axes[0].set_ylabel("sigma / moment (1 sigma)")
    axes[0].legend(title="gyro noise", fontsize=8, title_fontsize=8)
    fig.suptitle("identifiability: principal moments I1 (solid), I2 (dashed), I3 (dotted)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "identify_sweep.png")
    args = parser.parse_args()
    plot(sweep(), args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()

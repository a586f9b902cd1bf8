"""The worked example of docs/gym.md (tools/gym_pd_search.py) runs, quickly, and its search never loses to its start."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np

TOOL = Path(__file__).resolve().parents[2] / "tools" / "gym_pd_search.py"


def _tool():
    spec = importlib.util.spec_from_file_location("gym_pd_search", TOOL)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_search_keeps_the_best_and_never_loses_to_the_baseline_on_its_seeds():
    tool = _tool()
    seeds = list(range(100, 116))
    baseline = tool.evaluate(np.array([tool.BASELINE_GAINS]), seeds)
    assert 0.0 <= baseline.success_rate[0] <= 1.0
    gains, best, history = tool.cross_entropy_search(seeds, 2, 4, np.random.default_rng(0), tool.BASELINE_GAINS)
    assert best >= baseline.mean_return[0]
    assert history == sorted(history) and history[-1] == best
    again = tool.evaluate(gains[None, :], seeds)
    assert again.mean_return[0] == best  # the same seeds: the same episodes, bit for bit
    # two gains in one batch score as each alone
    both = tool.evaluate(np.array([tool.BASELINE_GAINS, gains]), seeds)
    assert both.mean_return.tolist() == [baseline.mean_return[0], best]


def test_the_example_runs_from_the_command_line():
    result = subprocess.run(
        [sys.executable, str(TOOL), "--episodes", "32", "--iterations", "2", "--population", "4", "--train", "16"],
        capture_output=True,
        text=True,
        timeout=600,
        check=True,
    )
    lines = result.stdout.splitlines()
    assert lines[0].startswith("32 test episodes")
    assert lines[2].startswith("PD kp=0.25 kd=0.7") and lines[3].startswith("CEM kp=")
    assert "cross-entropy search: 2 iterations x 4 candidates x 16 episodes" in lines[4]

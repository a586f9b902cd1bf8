"""rigid-rot bag info / bag repair / resim / plot on recordings (in-process, no DDS)."""

import sys
from pathlib import Path

import pytest

pytest.importorskip("rigid_rot_msgs.msg")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "recording"))
from test_resim import COMMANDS, record_like_the_node

from rigid_rot_sim.cli import main
from rigid_rot_sim.recording.reader import BagReader


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    path = tmp_path_factory.mktemp("bags") / "run.mcap"
    record_like_the_node(path, "torque_driven", 400, 10, COMMANDS)
    return path


def test_bag_info_lists_topics_counts_and_integrator(bag, capsys):
    assert main(["bag", "info", str(bag)]) == 0
    out = capsys.readouterr().out
    assert "complete" in out and "Integrator: rk4" in out
    assert "/rigid_rot_sim/state" in out and "rigid_rot_msgs/msg/RigidBodyState" in out
    assert "/tf" in out and "[reliable, volatile, depth 100]" in out
    # 400 steps of 1 ms, states every 10 steps: the last at 0.39 s, log times in sim time
    assert "Duration:   0.390 s (sim time" in out and "Start:      0.000000 s of sim time" in out


def test_bag_info_of_a_wall_clock_recording_says_so(tmp_path, capsys):
    path = tmp_path / "wall.mcap"
    record_like_the_node(path, "free_tumble", 50, 10, {}, log_time="wall")
    assert main(["bag", "info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "(wall clock)" in out and "s since epoch" in out
    assert BagReader(path).metadata["log_time"] == {"base": "wall"}


def test_bag_repair_restores_the_index_of_a_truncated_file(bag, tmp_path, capsys):
    crashed = tmp_path / "crashed.mcap"
    data = bag.read_bytes()
    crashed.write_bytes(data[: len(data) // 2])  # what a crash in the middle leaves, at worst
    assert not BagReader(crashed).complete
    assert main(["bag", "repair", str(crashed)]) == 0
    out = capsys.readouterr().out
    assert "repaired" in out and (tmp_path / "crashed.mcap.crashed").exists()
    assert BagReader(crashed).complete
    assert main(["bag", "repair", str(crashed)]) == 0
    assert "already complete" in capsys.readouterr().out


def test_resim_exit_codes_and_verdicts(bag, capsys):
    assert main(["resim", str(bag)]) == 0
    assert "BIT-EXACT" in capsys.readouterr().out
    assert main(["resim", str(bag), "--integrator", "lie_rk4"]) == 0
    assert "DIFFERS" in capsys.readouterr().out
    assert main(["resim", str(bag), "--integrator", "no_such_method"]) == 2
    assert "no_such_method" in capsys.readouterr().err


def test_plot_prints_the_files_it_wrote(bag, tmp_path, capsys):
    assert main(["plot", str(bag), "--out", str(tmp_path / "p")]) == 0
    printed = capsys.readouterr().out.split()
    assert len(printed) == 4 and all(Path(p).is_file() for p in printed)


def test_missing_file_is_a_one_line_error(tmp_path, capsys):
    assert main(["bag", "info", str(tmp_path / "nope.mcap")]) == 2
    assert "nope.mcap" in capsys.readouterr().err

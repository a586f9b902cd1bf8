"""Plots of a recorded run: four readable PNGs, and a clear error when there is nothing to plot."""

import numpy as np
import pytest

pytest.importorskip("rigid_rot_msgs.msg")
from test_resim import COMMANDS, record_like_the_node  # noqa: E402

from rigid_rot_sim.recording.plot import load_states, plot_run, principal_frame  # noqa: E402
from rigid_rot_sim.recording.reader import BagReader  # noqa: E402
from rigid_rot_sim.recording.writer import Recorder  # noqa: E402


@pytest.mark.parametrize("scene, commands", [("torque_driven", COMMANDS), ("free_tumble", {})])
def test_plot_writes_four_pngs(tmp_path, scene, commands):
    bag = tmp_path / "run.mcap"
    record_like_the_node(bag, scene, 600, 10, commands)
    written = plot_run(bag, tmp_path / "plots")
    assert [p.name for p in written] == ["omega.png", "drift.png", "torque.png", "polhode.png"]
    import matplotlib.image

    for path in written:
        image = matplotlib.image.imread(path)
        assert image.shape[0] > 400 and image.shape[1] > 600
        assert np.std(image) > 0.01  # not a blank canvas


def test_principal_frame_from_scene_and_from_the_recorded_states_agree(tmp_path):
    bag = tmp_path / "run.mcap"
    record_like_the_node(bag, "torque_driven", 600, 10, COMMANDS)
    reader = BagReader(bag)
    series = load_states(reader)
    moments, _ = principal_frame(reader, series)
    assert moments == pytest.approx([0.020, 0.030, 0.040])
    reader.metadata.pop("scene")  # force the least-squares fit L_body = I ω
    fitted, _ = principal_frame(reader, series)
    assert fitted == pytest.approx([0.020, 0.030, 0.040], rel=1e-9)


def test_recording_without_states_is_a_value_error(tmp_path):
    bag = tmp_path / "empty.mcap"
    with Recorder(bag) as recorder:
        recorder.add_topic("/x", "geometry_msgs/msg/WrenchStamped")
    with pytest.raises(ValueError, match="nothing to plot"):
        plot_run(bag, tmp_path / "plots")


def test_a_recording_with_reaction_wheels_gets_their_speeds_plotted(tmp_path):
    """``rigid-rot plot`` of a wheel run: wheels.png with each wheel's speed and torque (issue 40)."""
    from sensor_msgs.msg import JointState

    from rigid_rot_sim.recording.plot import wheel_figure

    bag = tmp_path / "wheels.mcap"
    with Recorder(bag) as recorder:
        recorder.add_topic("/rigid_rot_sim/wheels", "sensor_msgs/msg/JointState")
        for k in range(20):
            msg = JointState(name=["w1", "w2"], velocity=[10.0 * k, -5.0 * k], effort=[0.01, -0.02])
            msg.header.stamp.nanosec = k * 10_000_000
            recorder.write_message("/rigid_rot_sim/wheels", msg, k * 10_000_000)
    figure = wheel_figure(BagReader(bag))
    assert figure is not None
    speeds, torques = figure.axes
    assert [line.get_label() for line in speeds.get_lines()] == ["w1", "w2"]
    assert list(speeds.get_lines()[0].get_ydata()) == [10.0 * k for k in range(20)]
    assert list(torques.get_lines()[1].get_ydata()) == [-0.02] * 20
    no_wheels = tmp_path / "run.mcap"
    record_like_the_node(no_wheels, "free_tumble", 60, 10, {})
    assert wheel_figure(BagReader(no_wheels)) is None


def test_the_polhode_labels_do_not_overlap(tmp_path, monkeypatch):
    """The 3D plot's ω3 label used to run into the 2D plot's ω2 label (2 px apart; issue 40)."""
    from rigid_rot_sim.recording import plot

    figures = []
    monkeypatch.setattr(plot.plt, "close", figures.append)
    bag = tmp_path / "run.mcap"
    record_like_the_node(bag, "free_tumble", 600, 10, {})
    plot_run(bag, tmp_path / "plots")
    (figure,) = [f for f in figures if any(ax.name == "3d" for ax in f.axes)]
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    ax3 = next(ax for ax in figure.axes if ax.name == "3d")
    ax2 = figure.axes[1]
    texts = [ax3.zaxis.label, ax3.xaxis.label, ax3.yaxis.label]
    others = [ax2.yaxis.label, *ax2.get_yticklabels(), ax2.title]
    from matplotlib.transforms import Bbox

    for text in texts:
        box = text.get_window_extent(renderer)
        padded = Bbox.from_extents(box.x0 - 10, box.y0, box.x1 + 10, box.y1)  # 10 px apart at least (was 2)
        for other in others:
            if other.get_text():
                assert not padded.overlaps(other.get_window_extent(renderer)), (text.get_text(), other.get_text())

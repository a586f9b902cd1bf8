"""Viewers without ROS: a Foxglove WebSocket server for a live run (:mod:`.foxglove`) or a recording (:mod:`.playback`).

The body's own web page (viser, offline in any browser): :mod:`.web` draws it, :mod:`.web_playback`
plays a recording on it.

Built on :mod:`rigid_rot_sim.recording` (definitions, reader) and :mod:`rigid_rot_sim.run.body_view`
(what is drawn); used by :mod:`rigid_rot_sim.ros.foxglove_live` and ``rigid-rot view``.
"""

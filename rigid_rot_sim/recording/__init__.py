"""Recording runs to MCAP (rosbag2-compatible), reading them back, replay, re-simulation, plots.

Modules, one job each:

* :mod:`.definitions` - complete ``ros2msg`` definitions and type hashes (installed .msg
  files; ``tf2_msgs/msg/TFMessage`` embedded), CDR encoders/decoders from definitions;
* :mod:`.writer` - :class:`~.writer.Recorder`, the MCAP file rosbag2 reads as a lone-file bag;
* :mod:`.bag_metadata` - what rosbag2 reads besides the messages: offered QoS, topic
  records, the BagMetadata YAML (shared by the writer and ``repair``);
* :mod:`.session` - :class:`~.session.RunRecorder`, one simulator run (metadata, /tf, events);
* :mod:`.events` - the simulation event log that makes re-simulation exact;
* :mod:`.reader` - reading, crash recovery (scan) and ``repair``, ``info``;
* :mod:`.replay`, :mod:`.resim`, :mod:`.plot` - what the ``rigid-rot`` subcommands run;
* :mod:`.provenance` - package and dependency versions stored with each recording;
* :mod:`.aem` - CCSDS Attitude Ephemeris Messages from a recording.

Nothing here is imported by :mod:`rigid_rot_sim.core`, :mod:`rigid_rot_sim.scene` or
:mod:`rigid_rot_sim.run`. The node's side of recording (an observer of the simulator and a
listener of its messages) is :mod:`rigid_rot_sim.ros.recording`; here ROS is imported only
inside the functions that need it (replay, the writer's serialisation), so reading, resim and
plots work without ROS.
"""

#: Time bases of a recording's MCAP log times, the default first (see :mod:`.session`).
LOG_TIME_BASES = ("sim", "wall")

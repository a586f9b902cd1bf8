"""The ROS layer: the node and one small module per concern, like ros2/demos.

* :mod:`.node`: :class:`~.node.RigidRotSimNode` and :class:`~.node.SceneRun` (the wiring of the parts);
  :mod:`.parts`: the run's parts, each built from the scene, and the start-up line; :mod:`.node_process`:
  ``rclpy.init``, the run until it finishes, and ``main``;
* :mod:`.parameters`: declarations with descriptors, the validate / apply callbacks;
* :mod:`.outputs`: the publishers in one table keyed on the scene's output names, and the
  one path every message takes out of the node (:meth:`.outputs.Outputs.publish`);
* :mod:`.inputs`: the torque subscriptions and ``~/rejected``;
* :mod:`.services`: ``~/compute_inertia`` and the run's services; :mod:`.simulation_services`:
  the standard ``simulation_interfaces`` ones, through the same actions;
* :mod:`.wheel_inputs`: ``~/wheel_torque`` for the reaction wheels; :mod:`.rod_inputs`:
  ``~/magnetorquer_command`` for the torque rods; :mod:`.lockstep`: the read-only ``lockstep.*``
  parameters and the turn engine's wiring; :mod:`.simulate_steps`: the standard ``SimulateSteps``
  action; :mod:`.recording`: the node's recorder;
  :mod:`.foxglove_live`: the Foxglove live server; :mod:`.live_views`: the optional live viewers' wiring;
* :mod:`.run_loop`: the run loop (steps, commands, outputs; services on an executor thread);
  :mod:`.intake`: every command topic taken by the run loop in arrival order, losses counted;
  :mod:`.rclpy_internals`: every use of rclpy's internals (the run loop's waits and takes), in one place;
* :mod:`.joint_state_door`: the wheels' JointState door for ros2_control; :mod:`.paused_clock`: /clock
  while paused; :mod:`.sim_events`: the live ``~/sim_events``; :mod:`.topic_types`: publishers of a
  wrong type on a command topic, named in the log; :mod:`.web_live`: the body's web page of a live run;
* :mod:`.qos`: the QoS profiles. Message <-> numpy conversions: :mod:`rigid_rot_sim.conversions`.
* :mod:`.controller`: apart from the node, ``rigid-rot-controller``, a quaternion-feedback
  attitude controller and the template for a user's own; :mod:`.detumble_controller`: the B-dot
  detumble controller on ``~/magnetometer`` commanding the rods.

The physics is in :mod:`rigid_rot_sim.core`, the run and its pacing in :mod:`rigid_rot_sim.run` (no ROS): the
:class:`~rigid_rot_sim.run.simulator.Simulator` and the
:class:`~rigid_rot_sim.run.pacing.RunDriver` that advances it against the wall clock.
Both report to observers (:class:`~rigid_rot_sim.run.observer.SimulationObserver`): the
ROS outputs and the recorder.

A torque command's route, top to bottom
---------------------------------------
1. ``inputs.TorqueInputs.torque_callback(msg, source, topic)``: the handler of the topic, called by
   the run loop's ``intake.CommandIntake.drain`` for every message in arrival order (one subscription
   per topic input of the scene, created in ``TorqueInputs.__init__`` through ``CommandIntake.subscribe``).
2. ``conversions.torque_command_from_msg(msg)``: torque, force (WrenchStamped), frame_id and
   header stamp (s) as numpy arrays and floats.
3. ``run.simulator.Simulator.receive_torque(source, torque, frame_id, stamp, force)`` ->
   ``run.commands.CommandSchedule.admit``: the checks (finite, ``commands.max_torque``,
   zero force, the input's frame policy, the stamp horizon) and the effective time (the
   stamp, or now). A refusal raises ``CommandRejected``: the simulator reports it to its
   observers (``command_rejected``) and ``torque_callback`` publishes it on ``~/rejected``
   (``inputs.Rejections.reject`` -> ``outputs.Outputs.publish``).
4. ``Simulator.submit_torque`` -> ``CommandSchedule.submit``: a ``TorqueCommand`` goes on
   the schedule's event heap at the step where it takes effect; then every observer of the
   simulator hears ``command_accepted(step, command)``. The recorder
   (``ros.recording.NodeRecording.command_accepted``) writes it to
   ``~/sim_events`` as a ``torque`` event: what resim replays.
5. Back in ``torque_callback``: the message as received goes to the input listeners;
   ``NodeRecording.received`` records it on the torque topic.
6. Later, at the run loop's next turn (``run_loop.RunLoop``, ``node.SceneRun.turn``): ``node.SceneRun.tick`` ->
   ``run.pacing.RunDriver.tick`` (``Pacer.target_step``: the step due now) ->
   ``RunDriver.run`` -> ``Simulator.advance_to`` -> ``Simulator.advance`` ->
   ``run.stepper.Stepper.advance``: at the command's step ``CommandSchedule.process_due``
   makes it the input's held torque and sums what the inputs hold,
   ``Stepper.set_command_torque`` gives that sum to the integrator (principal frame), and
   the integrator steps with it.
7. After each slice, ``RunDriver.publish_due`` -> ``outputs.Outputs.outputs_due(step,
   snapshot, names)`` builds each due message (``outputs.OUTPUTS``) and
   ``Outputs.publish`` serialises it once, hands the bytes to ``NodeRecording.published``,
   which writes them to the file, then publishes the same bytes.

There is one route: no method or publisher is wrapped, and whether the run is recorded
only decides whether the recorder is among the observers and listeners
(``parts.recording``, ``recording.NodeRecording.attach``).
"""

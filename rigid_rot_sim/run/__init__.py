"""The run engine: a scene's simulation driven by commands, in steps, paced against a wall clock.

* :mod:`.simulator` - :class:`~.simulator.Simulator`, the engine's API (no ROS);
* :mod:`.stepper` - the integrator and the state, stepped in chunks between events;
* :mod:`.commands` - :class:`~.commands.CommandSchedule`: torque commands admitted, held, expired;
* :mod:`.clock` - :class:`~.clock.StepClock` and the one rule for which step a time lands on;
* :mod:`.observables` - :class:`~.observables.StateSnapshot` and the drift monitors;
* :mod:`.observer` - :class:`~.observer.SimulationObserver`, what the engine reports;
* :mod:`.pacing` - real-time pacing, output schedules and the run driver (fake-clock testable);
* :mod:`.advice` - stable step sizes and the ``auto`` method choice;
* :mod:`.timeline` - which scheduled torque acts over which steps, and the world -> body
  re-expression (the engine and the sweep);
* :mod:`.gyrostat_stepper` - the stepper of a spacecraft scene (reaction wheels); :mod:`.rod_torque` - the
  torque rods' torque on a step, in the Earth's field;
  :mod:`.joint_commands` - the rule of the wheels' JointState commands (ros2_control's door);
* :mod:`.sensors` - the scene's sensors and their sample sequences; :mod:`.digest` - the run digest;
* :mod:`.lockstep` - the run waits at each controller turn; :mod:`.step_requests` - steps of a
  paused run with their own input;
* :mod:`.body_view` - what a viewer draws of the body (inertia box, omega, L);
* :mod:`.detumble` - a B-dot detumble run in the engine on the scene's magnetometer and rods.

Built on :mod:`rigid_rot_sim.core` and :mod:`rigid_rot_sim.scene`; no ROS.
"""

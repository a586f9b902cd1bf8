"""Monte Carlo and parameter sweeps: many bodies of one scene, on a Dask cluster, into Parquet.

* :mod:`.spec`: sweep specs (a base scene, dispersions, grids) validated from YAML, against
  :mod:`.schema` (the JSON Schema and its defaults).
* :mod:`.draws`: the seeded random inputs, one stream per (run, kind), so a run's draws do not
  depend on how the sweep is cut into chunks.
* :mod:`.chunks`: a sweep's chunks and the batch simulation of one chunk (dispersions, torque
  noise, a segment plan and the batch kernel calls, failures); which torque acts over which steps
  comes from the run engine's :mod:`rigid_rot_sim.run.timeline`, so a sweep run is the engine's run.
* :mod:`.engine_runs`: the scenes the batch kernel cannot run (reaction wheels, gravity gradient),
  run by the engine itself on each sample's dispersed copy of the scene.
* :mod:`.bodies`: the bodies of a chunk and what their runs give back, whichever path ran them.
* :mod:`.checkpoints`: the rates kept at checkpoints and the events read from them.
* :mod:`.runner`: the chunks as tasks on :mod:`rigid_rot_sim.cluster`, gathered in run order.
* :mod:`.output`: the Parquet file, summary.md and plots of a sweep.

The ``rigid-rot sweep`` command drives it; nothing in the node imports it.
"""

"""Analysis of the numerical core: work-precision report and stability suite (sweeps: :mod:`rigid_rot_sim.sweep`).

* :mod:`.problems`: the benchmark problems P1 to P4 as data, with their references, and
  :meth:`~.problems.Problem.final_state`, a method's run of a problem to its end.
* :mod:`.metrics`: errors at the final time (omega, attitude angle, energy, |L|).
* :mod:`.workprecision`: error against run time for every integrator and scipy's solve_ivp;
  :mod:`.workprecision_report` runs it on the problems and writes the report.
* :mod:`.stability_cases`: the catalogue of stiff and extreme cases (data);
  :mod:`.stability` runs a case against its criterion, bisects for stable steps and runs
  the long horizon; :mod:`.stability_report` runs the suite and writes its outputs.
* :mod:`.report_io`: machine facts, number formats, markdown tables and JSON of both reports.
* :mod:`.plot`: matplotlib (Agg) figures of both (as :mod:`rigid_rot_sim.recording.plot` draws a recording).

Both run their independent tasks on :mod:`rigid_rot_sim.cluster` (dask.distributed, local or
an existing cluster), as the sweeps do; nothing here loads the sweep.

Nothing here is imported by the core or the node; the ``rigid-rot report`` and
``rigid-rot stability`` commands drive it.
"""

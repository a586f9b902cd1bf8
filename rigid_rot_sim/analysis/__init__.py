"""Analysis of the numerical core: work-precision report and stability suite.

* :mod:`.problems`: the benchmark problems P1 to P4 as data, with their references.
* :mod:`.metrics`: errors at the final time (omega, attitude angle, energy, |L|).
* :mod:`.workprecision`: error against run time for every integrator and scipy's solve_ivp.
* :mod:`.stability`: the catalogue of stiff and extreme cases, and bisection for stable steps.
* :mod:`.plotting`: matplotlib (Agg) figures of both.

Nothing here is imported by the core or the node; the ``rigid-rot report`` and
``rigid-rot stability`` commands drive it.
"""

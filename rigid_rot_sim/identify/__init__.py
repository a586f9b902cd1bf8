"""System identification: a body's inertia (and constant torque and gyro biases) from gyro and torque data.

Arrays in, a frozen result out, no ROS needed; ``rigid-rot identify`` (:mod:`rigid_rot_sim.cli.identify`)
is a thin shell over it. Modules:

* :mod:`rigid_rot_sim.identify.data`: :class:`~rigid_rot_sim.identify.data.Measurements` (gyro samples,
  attitude) and :class:`~rigid_rot_sim.identify.data.PiecewiseTorque` (piecewise-constant body torque);
* (the model, Euler's equations with parameter sensitivities, compiled RK4, is the core's
  :mod:`rigid_rot_sim.core.sensitivities`, precompiled with every other kernel);
* :mod:`rigid_rot_sim.identify.fit`: :func:`~rigid_rot_sim.identify.fit.identify`, equation error then
  output error, covariance and observability;
* :mod:`rigid_rot_sim.identify.report`: validation replays, the JSON object, the body YAML, the summary;
* :mod:`rigid_rot_sim.identify.plot`: the validation plots;
* :mod:`rigid_rot_sim.identify.bag`: :func:`~rigid_rot_sim.identify.bag.read_bag`, measurements from an
  MCAP file or a rosbag2 directory;
* :mod:`rigid_rot_sim.identify.nominal`: the nominal tensor from a body or scene YAML.

Conventions: SI units, the body frame of the measurements, quaternions (x, y, z, w) body -> world;
torque acting = commanded + torque_bias (body frame), gyro reading = true rate + gyro_bias.

Example (noise-free data from a known body recovers it)::

    >>> import numpy as np
    >>> from rigid_rot_sim.identify import Measurements, PiecewiseTorque, identify
    >>> from rigid_rot_sim.identify.report import simulate_window
    >>> J = np.array([[0.02, 0.001, 0.0], [0.001, 0.03, 0.002], [0.0, 0.002, 0.04]])
    >>> t = np.arange(2001) * 0.005
    >>> torque = PiecewiseTorque([0.0, 3.0, 6.0], [[0.01, 0.0, 0.0], [0.0, 0.01, 0.005], [0.0, 0.0, -0.01]])
    >>> truth = Measurements(t, np.zeros((t.size, 3)), torque)
    >>> omega = simulate_window(truth, J, np.array([0.2, -0.1, 0.3]), "truth").omega
    >>> result = identify(Measurements(t, omega, torque))
    >>> bool(np.allclose(result.inertia, J, rtol=1e-6, atol=1e-9)), result.identifiable
    (True, 'full')
"""

from __future__ import annotations

from rigid_rot_sim.identify.data import Measurements, PiecewiseTorque
from rigid_rot_sim.identify.fit import ESTIMATES, Identification, identify

__all__ = ["ESTIMATES", "Identification", "Measurements", "PiecewiseTorque", "identify"]

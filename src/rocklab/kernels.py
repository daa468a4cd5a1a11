"""The library's numba kernels, compiled ahead of the jobs that use them.

Numba compiles a kernel at its first call in a process and keeps it in an
on-disk cache beside its module; while that cache is cold every process
compiles for itself (the overturning engine about 12 s of CPU, in each map
job that starts before the cache is written).  ``make venv`` calls
:func:`compile_kernels` once after the install.
"""

import numpy as np


def compile_kernels() -> None:
    """Compile every numba kernel of the library into numba's on-disk cache,
    with the argument types of the library's own calls: the overturning
    engine (:func:`rocklab.simulation.batch.compile_kernels`), the
    diagnosis's noise model (:func:`rocklab.diagnosis.estimation.noise.noise_variance`)
    and the flights' quadratures (the excursions into a gap too) and Newton passes (:mod:`rocklab.physics.flight`),
    and the rigid-body fit of a test's transducers (:mod:`rocklab.lab.kinematics_kernels`: the solve with and
    without the sliding v, the model with and without its derivatives, the channels' leverage)."""
    from rocklab.diagnosis.estimation.noise import noise_variance
    from rocklab.lab import channel_gain, kinematics
    from rocklab.physics import flight
    from rocklab.simulation.batch import compile_kernels as compile_engine

    compile_engine()
    noise_variance(np.array([0.1, -0.2, 0.05, 0.3, -0.1]), np.array([0.5, 1.0, 2.0, 0.2, 0.1]))
    # every compiled path: the quadratures, dry friction with drag and a viscous loss on a rounded hinge
    A, a, p = np.array([0.02, 0.05]), np.array([0.1, 0.1]), np.array([2.0, 2.0])
    flight.quarter_period(A, a, p)
    flight.apex_after(flight.landing_speed(A, a, p), a, p, zeta=0.01, mu=0.01, kappa=0.1, k=0.1)
    flight.excursion_time(np.array([0.3, 0.2]), np.array([0.2, 0.1]), 0.1 * A, a, p)
    # a wall of the lab's usual layout rocking a little: the solve (its start, iteration and residual) as a
    # reduction calls it, and the leverage of the gain check
    wall = np.array([[-500.0, 125.0, 300.0], [-500.0, -125.0, 300.0], [500.0, 125.0, 900.0], [500.0, -125.0, 900.0]])
    frame = wall + np.array([0.0, 200.0, 0.0])
    theta = np.linspace(-0.02, 0.02, 8)
    zero = np.zeros_like(theta)
    readings = kinematics.transducer_elongation(theta, zero, zero, zero, wall, frame, 250.0)
    for solve_v in (True, False):
        kinematics.solve_wall_motion(readings, wall, frame, 250.0, weights=np.ones(4), solve_v=solve_v)
    channel_gain.leverage(kinematics.elongation_jacobian(theta, zero, zero, zero, wall, frame, 250.0)[:, :, [0, 1, 3]])

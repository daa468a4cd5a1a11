"""rocklab.kernels: what ``make venv`` compiles covers the library's calls."""

import numpy as np

from rocklab.diagnosis.estimation import noise
from rocklab.kernels import compile_kernels
from rocklab.physics import flight
from rocklab.simulation import engine


def test_compile_kernels_covers_the_diagnosis_and_the_engine():
    compile_kernels()
    # the profile likelihood is compiled inside its compiled search (noise._profile_minimum)
    before = {k: set(f.signatures) for k, f in [("profile", noise._profile_minimum), ("engine", engine.batch_kernel)]}
    assert all(before.values())
    rng = np.random.default_rng(1)
    # residuals of a fit as the engine passes them: float64 slices, some not contiguous
    r, x = rng.normal(size=40), rng.uniform(0.05, 3.0, size=40)
    s0, s1 = noise.noise_variance(r[::2], x[::2])
    assert s0 > 0 and s1 >= 0
    assert set(noise._profile_minimum.signatures) == before["profile"]
    assert set(engine.batch_kernel.signatures) == before["engine"]


def test_compile_kernels_covers_the_flights_of_a_fit():
    compile_kernels()
    kernels = [flight._newton_apex, flight._path_nodes, flight._quarter_period_nodes, flight._moments_of]
    before = [set(f.signatures) for f in kernels]
    assert all(before)
    # a padded (tests, impacts) stack as the diagnosis passes it, per-flight losses as broadcast scalars
    A = np.array([[0.03, 0.02, np.nan], [0.05, 0.01, 0.005]])
    a, p = np.full_like(A, 0.1), 2.0
    v = flight.landing_speed(A, a, p, zeta=0.02, mu=0.01, kappa=0.2, k=0.1)
    assert np.isfinite(flight.apex_after(v, a, p, zeta=0.02, mu=0.01, kappa=0.2, k=0.1)[1]).all()
    flight.quarter_period(A, a, p)
    assert [set(f.signatures) for f in kernels] == before

"""rocklab.kernels: what ``make venv`` compiles covers the library's calls."""

import numpy as np

from rocklab.diagnosis.estimation import noise
from rocklab.kernels import compile_kernels
from rocklab.simulation import engine


def test_compile_kernels_covers_the_diagnosis_and_the_engine():
    compile_kernels()
    before = {k: set(f.signatures) for k, f in [("profile", noise._profile), ("engine", engine.batch_kernel)]}
    assert all(before.values())
    rng = np.random.default_rng(1)
    # residuals of a fit as the engine passes them: float64 slices, some not contiguous
    r, x = rng.normal(size=40), rng.uniform(0.05, 3.0, size=40)
    s0, s1 = noise.noise_variance(r[::2], x[::2])
    assert s0 > 0 and s1 >= 0
    assert set(noise._profile.signatures) == before["profile"]
    assert set(engine.batch_kernel.signatures) == before["engine"]

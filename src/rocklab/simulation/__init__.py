"""The rocking simulator: model (Sect. 1), solve_ivp reference, numba engine, batch runs."""

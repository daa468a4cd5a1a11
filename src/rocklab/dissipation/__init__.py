"""Energy dissipation of free-rocking tests (Sects. 3-4): per-test coefficients, series statistics, Table 3."""

"""Real shake-table outcomes: the ASU tests of two granite replicas of a rocking boulder.

The data (``shake_table_dir``, GPL-3.0, never copied into this repository)
hold per test the table motion, whether each specimen overturned and the
predictions of a discrete-element model.  Modules:

- :mod:`.records`: the test table, the geometry and each test's table motion
  as an obspy Stream (offset removed, sign checked against the displacement);
- :mod:`.block`: the planar rocking block of each specimen (both edges, the
  exact form, Housner's e) and its outcome under every record and cause
  parameter (batch engine);
- :mod:`.calibration`: the causes of the catalogue fitted to a Bernoulli
  likelihood of the outcomes, cross-validated by ground motion, with the
  PGV-threshold baseline and the DEM predictions;
- :mod:`.evaluation`: scores, what the nominal block gets wrong, fragility
  tables and overturning maps of the calibrated block.
"""

"""Real shake-table outcomes: the ASU tests of two granite replicas of a rocking boulder.

The data (``shake_table_dir``, GPL-3.0, never copied into this repository)
hold per test the table motion, whether each specimen overturned and the
predictions of a discrete-element model.  Modules:

- :mod:`.records`: the test table, the geometry and each test's table motion
  as an obspy Stream (offset removed, sign checked against the displacement);
- :mod:`.block`: the planar rocking block of each specimen on its contact
  (contact edges in mm from the centre of mass, the body's own inertia, the
  e of an asymmetric body, a bounded extra loss) and its outcome under every
  record at every node of its grid (batch engine);
- :mod:`.calibration`: the contact fitted to a Bernoulli likelihood of the
  outcomes, folds and resamples by earthquake record, the paired interval
  of an accuracy difference, the PGV-threshold baseline;
- :mod:`.evaluation`: held-out scores against the PGV threshold and the DEM
  predictions, transfer between the replicas, what the nominal block gets
  wrong, fragility tables and overturning maps of the calibrated block;
- :mod:`.summary`: the numbers of the docs page.
"""

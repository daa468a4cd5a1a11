"""Physical constants of the library, one home each (no import beyond the standard library)."""

#: Standard gravity [m/s^2] (CGPM 1901): the one value of g of the library, from the walls'
#: equation of motion to the unit "g" of accelerograms and the accelerometer of an inertial record.
G = 9.80665

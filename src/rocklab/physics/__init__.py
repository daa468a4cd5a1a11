"""Rigid-wall physics of the paper.

Geometry (Eqs. 9, 16), coefficients of restitution (Eqs. 1-2, 10-17),
impact laws, the closed forms of a flight, and the laws a cause of the
diagnosis declares (:mod:`rocklab.physics.law`).
"""

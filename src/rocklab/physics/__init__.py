"""Rigid-wall physics of the paper.

Geometry (Eqs. 9, 16), coefficients of restitution (Eqs. 1-2, 10-17) and
impact laws.
"""

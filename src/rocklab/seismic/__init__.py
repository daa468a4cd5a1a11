"""Recorded ground motions (obspy readers) and overturning maps (Sect. 5, Figs. 21-23)."""

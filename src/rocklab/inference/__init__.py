"""Statistics the stages share: intervals on the units a value rests on, multiplicity, table notes.

Below :mod:`rocklab.dissipation` and :mod:`rocklab.diagnosis`, which both
import it; it imports neither.
"""

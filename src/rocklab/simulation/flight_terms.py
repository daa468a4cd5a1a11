"""The numba engine's terms in flight: their slots in its parameter vector and their compiled function.

A term of the equation of motion between impacts is declared once, by its
law (:class:`rocklab.physics.law.FlightTerm`); here the terms of the walls
of one batch become what the engine (:mod:`rocklab.simulation.engine`)
takes: each its parameters in the ``flight_*`` slots of the vector
(:func:`flight_slots`) and all of them one compiled function of the state,
the sum of their decelerations (:func:`flight_function`), which the kernel
takes as an argument: a first-class function of one type whatever the
terms, so that the kernel compiled into numba's on-disk cache serves every
wall.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence

import numba
from numba.core.ccallback import CFunc
from numba.core.dispatcher import Dispatcher

from rocklab.physics.law import FlightTerm
from rocklab.simulation.engine import FLIGHT_SLOTS, LAYOUT, FlightFunction, Params, slot

#: Slot of p [rad/s], which every deceleration takes.
_P = slot("p")


def flight_slots(terms: Sequence[FlightTerm]) -> dict[FlightTerm, int]:
    """First slot of each term in flight of ``terms`` (:class:`rocklab.physics.law.FlightTerm`, in their
    order) in the engine's parameter vector, its parameters after it.

    Raises
    ------
    NotImplementedError
        For terms of more parameters than the vector's :data:`rocklab.simulation.engine.FLIGHT_SLOTS`.
    """
    out, i = {}, slot(FLIGHT_SLOTS[0])
    for term in terms:
        out[term] = i
        i += len(term.params)
    if i > len(LAYOUT):
        names = ", ".join(t.name for t in terms)
        raise NotImplementedError(f"the engine holds {len(FLIGHT_SLOTS)} parameters of terms in flight: {names}")
    return out


#: The type of the engine's function of the terms in flight: (theta [rad], thetadot [rad/s], parameter
#: vector) -> deceleration [rad/s^2].
FLIGHT_TYPE = numba.types.float64(
    numba.types.float64,
    numba.types.float64,
    # numba's type constructors are not annotated
    numba.types.UniTuple(numba.types.float64, len(LAYOUT)),  # type: ignore[no-untyped-call]
)


def _zero(x: float, v: float, prm: Params) -> float:
    return 0.0


@functools.cache
def _no_terms() -> CFunc:
    # compiled on first use, not on import: a cfunc compiles when it is made
    return numba.cfunc(FLIGHT_TYPE, cache=True)(_zero)


def _plus(rest: FlightFunction, deceleration: Callable[..., float], i: int) -> Dispatcher[FlightFunction]:
    """The function ``rest`` of the terms before it plus the ``deceleration`` of one more, its parameters
    from slot ``i`` on."""

    @numba.njit
    def total(x: float, v: float, prm: Params) -> float:
        return rest(x, v, prm) + deceleration(x, v, prm[_P], prm, i)

    return total


@functools.cache
def flight_function(terms: tuple[FlightTerm, ...] = ()) -> CFunc:
    """The engine's function of the decelerations of ``terms`` in flight (in the slots of
    :func:`flight_slots`), compiled.

    The walls of one batch share it: a wall without terms in flight never
    calls it (its slot ``terms`` 0).  The function of no terms is cached
    on disk; that of a wall's own terms is compiled once per process.
    """
    if not terms:
        return _no_terms()
    total: Dispatcher[FlightFunction] = numba.njit(_zero)
    for term, i in flight_slots(terms).items():
        total = _plus(total, numba.njit(term.deceleration), i)
    return numba.cfunc(FLIGHT_TYPE)(total.py_func)

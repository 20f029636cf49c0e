"""Rotary position arithmetic for the path-recovery add-on instruction (pure functions).

A rotary axis has an unwind ``U > 0``: positions are taken modulo ``U`` in ``[0, U)``.
A linear axis has ``U == 0`` and positions are used as they are.  See INT-024/INT-025.
"""

from __future__ import annotations

import math

#: Move types of Cfg_MoveType (003 §2.2).
ABSOLUTE, SHORTEST, POSITIVE, NEGATIVE = 0, 2, 3, 4
MOVE_TYPES = (ABSOLUTE, SHORTEST, POSITIVE, NEGATIVE)


def unwind(position: float, u: float) -> float:
    """``position`` in ``[0, u)`` on a rotary axis; unchanged when ``u`` is 0 (linear)."""
    if u <= 0 or not math.isfinite(position):
        return position
    r = math.fmod(position, u)
    if r < 0:
        r += u
    return 0.0 if r >= u else r


def signed_distance(start: float, target: float, u: float, move_type: int) -> float:
    """The signed travel from ``start`` to ``target`` with ``move_type``.

    Absolute (and any type on a linear axis) travels ``target - start`` (positions
    unwound first on a rotary axis); positive travels forward by ``(target - start) mod u``;
    negative backward by the complement; shortest by the smaller of the two, forward on a tie.
    """
    if u <= 0 or move_type == ABSOLUTE or move_type not in MOVE_TYPES:
        return unwind(target, u) - unwind(start, u)
    forward = unwind(target - start, u)
    backward = -unwind(u - forward, u) if forward else 0.0
    if move_type == POSITIVE:
        return forward
    if move_type == NEGATIVE:
        return backward
    return forward if forward <= -backward else backward


def effective_move_type(start: float, target: float, u: float, move_type: int, tolerance: float) -> int:
    """Cfg_MoveType, except that a rotary-shortest distance strictly below the tolerance
    always moves rotary shortest (003 §2.2 Cfg_RotaryShortestTOL; INT-025)."""
    if u > 0 and math.isfinite(tolerance) and abs(signed_distance(start, target, u, SHORTEST)) < tolerance:
        return SHORTEST
    return move_type

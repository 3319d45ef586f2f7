"""Checks of scalar options at the public boundary, one message style everywhere.

Every public function checks each option before any work: numbers must be finite and in range,
counts integral, choices known. The message names the option, states the rule and repeats the
value, e.g. ``tol must be a finite number > 0, got nan``.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from typing import Any

from meshrepair.errors import MeshRepairError

__all__ = ["check_bool", "check_choice", "check_int", "check_number"]


def _bounds(low, high, low_open, high_open) -> str:
    parts = []
    if low is not None:
        parts.append(f"{'>' if low_open else '>='} {low:g}")
    if high is not None:
        parts.append(f"{'<' if high_open else '<='} {high:g}")
    if len(parts) == 2 and low is not None and high is not None:
        lb = "(" if low_open else "["
        rb = ")" if high_open else "]"
        return f"in {lb}{low:g}, {high:g}{rb}"
    return " and ".join(parts)


def check_number(name: str, value: Any, *, low: float | None = None, high: float | None = None,
                 low_open: bool = False, high_open: bool = False,
                 allow_none: bool = False) -> float | None:
    """``float(value)`` if it is a finite real number within the bounds, else MeshRepairError.

    ``low_open``/``high_open`` make the bound strict. ``None`` is returned as is if
    ``allow_none``.
    """
    if value is None and allow_none:
        return None
    rule = "a finite number" + (f" {_bounds(low, high, low_open, high_open)}"
                                if low is not None or high is not None else "")
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise MeshRepairError(f"{name} must be {rule}, got {value!r}")
    v = float(value)
    ok = math.isfinite(v)
    if ok and low is not None:
        ok = v > low if low_open else v >= low
    if ok and high is not None:
        ok = v < high if high_open else v <= high
    if not ok:
        raise MeshRepairError(f"{name} must be {rule}, got {value!r}")
    return v


def check_angle(name: str, value: Any) -> float:
    """A dihedral threshold in degrees: a finite number (not a bool) in the open range
    (0, 180)."""
    if not isinstance(value, bool) and isinstance(value, numbers.Real):
        v = float(value)
        if math.isfinite(v) and 0 < v < 180:
            return v
    raise MeshRepairError(f"{name} must be an angle in degrees in (0, 180), got {value!r}")


MAX_ITERATIONS = 100_000
"""The most ADMM iterations one call accepts (per stage): the defaults run 30-150 and the
solves stop on their tolerance well before; a larger count is a typing slip that would run for
days, refused before any work."""

MAX_INNER_ITERATIONS = 1_000
"""The most V-subproblem iterations per ADMM iteration (the default is 3)."""


def is_whole(value: Any) -> bool:
    """A finite whole number that is not a bool: ``2``, ``2.0``, ``np.int64(2)``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return False
    v = float(value)
    return math.isfinite(v) and v == int(v)


def check_callable(name: str, value: Any) -> None:
    """MeshRepairError unless ``value`` is None or callable."""
    if value is not None and not callable(value):
        raise MeshRepairError(f"{name} must be callable or None, got {type(value).__name__}")


def check_int(name: str, value: Any, *, low: int | None = None, high: int | None = None,
              allow_none: bool = False) -> int | None:
    """``int(value)`` if it is an integer (an integral float is accepted) within
    ``[low, high]``, else MeshRepairError."""
    if value is None and allow_none:
        return None
    rule = "an integer" + (f" {_bounds(low, high, False, False)}"
                           if low is not None or high is not None else "")
    if not is_whole(value):
        raise MeshRepairError(f"{name} must be {rule}, got {value!r}")
    iv = int(float(value))
    if (low is not None and iv < low) or (high is not None and iv > high):
        raise MeshRepairError(f"{name} must be {rule}, got {value!r}")
    return iv


def check_choice(name: str, value: Any, choices: Sequence[str]) -> str:
    """``value`` if it is one of ``choices``, else MeshRepairError listing them."""
    if not isinstance(value, str) or value not in choices:
        raise MeshRepairError(f"{name} must be one of {', '.join(map(repr, choices))}, "
                              f"got {value!r}")
    return value


def check_bool(name: str, value: Any) -> bool:
    """``bool(value)`` for True/False (numpy bools too), else MeshRepairError."""
    if isinstance(value, bool) or type(value).__name__ == "bool_":
        return bool(value)
    raise MeshRepairError(f"{name} must be True or False, got {value!r}")

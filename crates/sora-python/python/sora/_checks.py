"""Argument checks made before any work: a number or an integer of the
right type and range, or a one-line ``TypeError`` (a wrong type, ``None``
where a value is needed) or ``ValueError`` (a value out of range, with the
library's wording: ``name = value unit is out of range: allowed ...``).

Python's own conversions would raise ``OverflowError`` (``float(10**400)``,
a negative count for an unsigned integer) or ``MemoryError``; these checks
raise what the package documents instead."""

from __future__ import annotations

import math
import numbers
from typing import Optional

import numpy as np


def _shown(value) -> str:
    """A value for a message: short, even for an integer of 400 digits."""
    text = repr(value)
    return text if len(text) <= 24 else f"{text[:12]}...({len(text)} characters)"


def _type_name(value) -> str:
    return "None" if value is None else type(value).__name__


def number(name: str, value, unit: str, low: float = -math.inf, high: float = math.inf) -> float:
    """``value`` as a finite float in ``low..=high`` (in ``unit``, which
    may be empty)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number, not {_type_name(value)}")
    unit = f" {unit}" if unit else ""
    try:
        result = float(value)
    except OverflowError:
        raise ValueError(
            f"{name} = {_shown(value)}{unit} is out of range: it is not a finite number"
        ) from None
    if not math.isfinite(result):
        # Written as the library writes them (NaN, inf, -inf).
        shown = "NaN" if math.isnan(result) else str(result)
        raise ValueError(f"{name} = {shown}{unit} is not a finite number")
    if not low <= result <= high:
        raise ValueError(f"{name} = {result}{unit} is out of range: allowed {low}..={high}{unit}")
    return result


def optional_number(name: str, value, unit: str, low: float = -math.inf, high: float = math.inf) -> Optional[float]:
    """As :func:`number`, with ``None`` passed through."""
    return None if value is None else number(name, value, unit, low, high)


def integer(name: str, value, low: int, high: int, what: str = "") -> int:
    """``value`` as an int in ``low..=high`` (an integral number: a float
    such as ``512.0`` is refused, as a count must be whole)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an integer{what}, not {_type_name(value)}")
    result = int(value)
    if not low <= result <= high:
        raise ValueError(f"{name} = {_shown(result)} is out of range: allowed {low}..={high}")
    return result


def optional_integer(name: str, value, low: int, high: int, what: str = "") -> Optional[int]:
    """As :func:`integer`, with ``None`` passed through."""
    return None if value is None else integer(name, value, low, high, what)


def text(name: str, value, choices=None) -> str:
    """``value`` as a str (one of ``choices`` when given, else any)."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a str, not {_type_name(value)}")
    if choices is not None and value not in choices:
        listed = ", ".join(repr(c) for c in choices)
        raise ValueError(f"{name} = {value!r} is unknown: use {listed}")
    return value


def flag(name: str, value) -> bool:
    """``value`` as a bool (True, False, or a numpy bool)."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, not {_type_name(value)}")
    return bool(value)

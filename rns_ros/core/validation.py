"""Edge checks shared by the core: shape, finiteness, range; errors name the bad value."""

from __future__ import annotations

import math
import reprlib
from enum import StrEnum
from typing import Self, TypeVar

import numpy as np

from rns_ros.core.errors import ConfigError, InputError

StrEnumT = TypeVar("StrEnumT", bound=StrEnum)


class _BoundedRepr(reprlib.Repr):
    """:mod:`reprlib` with a few more items shown, and any integer printable."""

    def __init__(self) -> None:
        super().__init__()
        self.maxlevel = 3
        self.maxlist = self.maxtuple = self.maxset = self.maxfrozenset = self.maxdeque = 8
        self.maxdict = 8
        self.maxstring = self.maxother = 200
        self.maxlong = 60

    def repr_int(self, x: int, level: int) -> str:
        if x.bit_length() > 1000:  # str() refuses more than 4300 digits
            return f"<int of {x.bit_length()} bits>"
        return super().repr_int(x, level)


_SHORT = _BoundedRepr()


def short_repr(value, limit: int = 80) -> str:
    """``repr(value)`` for an error message, at most about ``limit`` characters: a longer one is
    cut with ``...`` and followed by the value's length, e.g. ``'aaaa...' (str of 5000
    characters)``. Its cost is bounded whatever the size of ``value`` (nested aliases of a YAML
    file stand for billions of items)."""
    text = _SHORT.repr(value)
    if len(text) <= limit and "..." not in text and "<int of" not in text:
        return repr(value)  # small: the exact repr, dict order kept
    if len(text) > limit:
        text = text[: max(limit - 3, 1)] + "..."
    try:
        size = len(value)
    except TypeError:
        return text
    unit = "characters" if isinstance(value, str | bytes) else "items"
    return f"{text} ({type(value).__name__} of {size} {unit})"


def as_vector(value, size: int, name: str) -> np.ndarray:
    """Return ``value`` as a finite float vector, shape ``(size,)``, else raise InputError."""
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputError(f"{name} must be numeric, got {short_repr(value)}") from exc
    if array.shape != (size,):
        raise InputError(f"{name} must have shape ({size},), got shape {array.shape}")
    if not np.isfinite(array).all():
        raise InputError(f"{name} must be finite, got {array.tolist()}")
    return array


def as_matrix(value, name: str) -> np.ndarray:
    """Return ``value`` as a finite 2-D float array or raise :class:`InputError`."""
    array = np.asarray(value, dtype=float)
    if array.ndim != 2 or 0 in array.shape:
        raise InputError(f"{name} must be a non-empty 2-D matrix, got shape {array.shape}")
    if not np.isfinite(array).all():
        raise InputError(f"{name} must be finite")
    return array


def positive(value: float, name: str, unit: str = "") -> float:
    """Return ``value`` as float if it is finite and > 0, else raise :class:`ConfigError`."""
    try:
        number = float(value)
    except (TypeError, ValueError, OverflowError):
        number = math.nan
    if not np.isfinite(number) or number <= 0.0:
        raise ConfigError(
            f"{name} must be a finite number > 0 {unit}".rstrip() + f", got {short_repr(value)}"
        )
    return number


def parse_choice(choices: type[StrEnumT], value, name: str) -> StrEnumT:
    """Member of the string enum ``choices`` named by ``value``, else ConfigError listing them."""
    try:
        return choices(value)
    except ValueError:
        valid = [member.value for member in choices]
        raise ConfigError(f"{name} must be one of {valid}, got {short_repr(value)}") from None


class Choice(StrEnum):
    """A string enum read from configuration: ``parse`` accepts a member or its value and raises
    :class:`ConfigError` listing the valid values. Subclasses name the setting in ``__label__``."""

    @classmethod
    def parse(cls, value) -> Self:
        if isinstance(value, cls):
            return value
        return parse_choice(cls, value, getattr(cls, "__label__", cls.__name__))


def apart(*values: float, digits: int = 4) -> list[str]:
    """``values`` as text with at least ``digits`` significant digits, and as many more (up to
    17) as it takes for values that differ to read differently: a position just past a limit
    never prints as the limit itself (2.2300004 against 2.23)."""
    numbers = [float(value) for value in values]
    for precision in range(digits, 18):
        texts = [f"{value:.{precision}g}" for value in numbers]
        if all(
            (texts[i] == texts[j]) == (numbers[i] == numbers[j])
            for i in range(len(numbers))
            for j in range(i + 1, len(numbers))
        ):
            return texts
    return [repr(value) for value in numbers]

"""Edge checks shared by the core: shape, finiteness, range; errors name the bad value."""

from __future__ import annotations

from enum import StrEnum
from typing import Self, TypeVar

import numpy as np

from rns_ros.core.errors import ConfigError, InputError

StrEnumT = TypeVar("StrEnumT", bound=StrEnum)


def as_vector(value, size: int, name: str) -> np.ndarray:
    """Return ``value`` as a finite float vector, shape ``(size,)``, else raise InputError."""
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be numeric, got {value!r}") from exc
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
    number = float(value)
    if not np.isfinite(number) or number <= 0.0:
        raise ConfigError(
            f"{name} must be a finite number > 0 {unit}".rstrip() + f", got {value!r}"
        )
    return number


def parse_choice(choices: type[StrEnumT], value, name: str) -> StrEnumT:
    """Member of the string enum ``choices`` named by ``value``, else ConfigError listing them."""
    try:
        return choices(value)
    except ValueError:
        valid = [member.value for member in choices]
        raise ConfigError(f"{name} must be one of {valid}, got {value!r}") from None


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

"""The one exception type for bad user input.

Usual call: ``raise InputError("speed must be >= 0 km/h, got -3")``.

Library functions raise :class:`InputError` with a message that names the field,
the allowed range and the value received; the CLI prints that message alone and
exits with status 2. Anything else escaping is a bug and keeps its traceback.
"""

from __future__ import annotations

import math

__all__ = ["InputError", "RunError", "cut", "positive"]


class InputError(ValueError):
    """Invalid user input: the message names the field, the allowed range and the value."""


class RunError(RuntimeError):
    """A valid request that could not be carried out (diverged simulation, no OpenGL, ...)."""


def positive(name: str, value: object, unit: str) -> float:
    """`value` as a float if it is a finite number > 0, else :class:`InputError` naming `name` and
    `unit` (e.g. ``positive("dt", dt, "s")``)."""
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a finite number > 0 {unit}, got {value!r}") from None
    if not math.isfinite(number) or number <= 0.0:
        raise InputError(f"{name} must be a finite number > 0 {unit}, got {value!r}")
    return number


def cut(text: str, limit: int = 200) -> str:
    """`text` cut to `limit` characters (with "…" and its full length) for an error message."""
    return text if len(text) <= limit else f"{text[:limit]}… ({len(text):,} characters)"

"""The one exception type for bad user input.

Usual call: ``raise InputError("speed must be >= 0 km/h, got -3")``.

Library functions raise :class:`InputError` with a message that names the field,
the allowed range and the value received; the CLI prints that message alone and
exits with status 2. Anything else escaping is a bug and keeps its traceback.
"""

from __future__ import annotations

__all__ = ["InputError", "RunError"]


class InputError(ValueError):
    """Invalid user input: the message names the field, the allowed range and the value."""


class RunError(RuntimeError):
    """A valid request that could not be carried out (diverged simulation, no OpenGL, ...)."""

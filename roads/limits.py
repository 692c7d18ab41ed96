"""Limits of a road's sampling grid, in m; plain numbers that import nothing.

Usual call: ``if spacing_m > MAX_SPACING_M: ...``.

Kept apart from :mod:`suvtwin.roads.spec` (which imports pydantic and numpy) so that
the command line can state them in its help without loading either.
"""

from __future__ import annotations

__all__ = ["MAX_SPACING_M", "MIN_RECOMMENDED_LENGTH_M"]

MAX_SPACING_M = 0.05
"""Coarsest grid spacing, m: its Nyquist frequency 1/(2·0.05) = 10 cycles/m is the
upper end of the generated band (Brancati & Tufano 2022, §2: Δ ≤ 1/(2·Ω_U))."""

MIN_RECOMMENDED_LENGTH_M = 100.0
"""Shortest road that holds one wavelength of the 0.01 cycle/m lower band edge, m."""

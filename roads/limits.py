"""Limits of a road's sampling grid, in m; plain numbers that import nothing.

Usual call: ``if spacing_m > MAX_SPACING_M: ...``.

Kept apart from :mod:`suvtwin.roads.spec` (which imports pydantic and numpy) so that
the command line can state them in its help without loading either.
"""

from __future__ import annotations

__all__ = [
    "MAX_ROAD_LENGTH_M",
    "MAX_ROAD_SAMPLES",
    "MAX_SPACING_M",
    "MAX_TRACK_SPACING_M",
    "MIN_RECOMMENDED_LENGTH_M",
    "TRACK_SPACING_M",
]

MAX_SPACING_M = 0.05
"""Coarsest grid spacing, m: its Nyquist frequency 1/(2·0.05) = 10 cycles/m is the
upper end of the generated band (Brancati & Tufano 2022, §2: Δ ≤ 1/(2·Ω_U))."""

MIN_RECOMMENDED_LENGTH_M = 100.0
"""Shortest road that holds one wavelength of the 0.01 cycle/m lower band edge, m."""

MAX_ROAD_LENGTH_M = 200_000.0
"""Longest road, m: 200 km, over an hour at 200 km/h (a longer drive is several roads)."""

MAX_ROAD_SAMPLES = 20_000_000
"""Most grid points of a road (length/spacing + 1): two tracks of 20 million float64 samples are
320 MB, the most a road may take in memory (200 km at 0.01 m)."""

TRACK_SPACING_M = 1.62
"""Default distance between a road's two wheel tracks for isotropic tracks, m: the SUV's mean track
(1.606 m front, 1.636 m rear)."""

MAX_TRACK_SPACING_M = 5.0
"""Widest distance between the two wheel tracks, m."""

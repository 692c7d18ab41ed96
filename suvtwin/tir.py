r"""Reading TNO MF-Tyre property files (``.tir``): sections of ``KEY = value`` in the file's units.

Usual call: ``tir = read_tir(path); kt0 = tir.number("VERTICAL", "VERTICAL_STIFFNESS", "force/length")``.

The format, as MF-Tyre 6.1 files and the tools that read them (Adams, CarMaker, Chrono,
MFeval) use it:

- ``[SECTION]`` lines open a section; ``KEY = value`` lines fill it. Keys and section
  names are case-insensitive (stored upper-case).
- A value is a number (``264700``, ``-1.5e-3``) or a quoted string (``'meter'``,
  ``"newton"``). Text after ``$`` outside quotes is a comment, and so is a whole line
  starting with ``$`` or ``!``.
- A line starting with ``{`` opens a table (e.g. ``[SHAPE]``'s ``{radial width}``): the
  rows of numbers after it, up to the next section, are kept as rows of floats.
- ``[UNITS]`` names the unit of LENGTH, FORCE, ANGLE, MASS, TIME and, optionally,
  PRESSURE (otherwise FORCE/LENGTH²). :meth:`TirFile.number` converts a value to SI
  given its dimension (``"length"``, ``"force/length"``, ``"force*time/length"``,
  ``"pressure"``; ``""`` for a dimensionless coefficient).

Anything else (a line that is not ``KEY = value``, a key given twice in one section, a
non-number where a number is needed, an unknown unit, a missing key) raises
:class:`~suvtwin.errors.InputError` with one message naming the file, the line (where
there is one) and the key.

References
----------
.. [1] TNO Automotive, *MF-Tyre/MF-Swift 6.1 Equation Manual*, and the tyre property file
   format it reads (the ``.tir`` files of MFeval and Project Chrono follow it).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from suvtwin.errors import InputError

__all__ = ["TirFile", "read_tir"]

_UNIT_FACTORS = {
    "LENGTH": {"meter": 1.0, "meters": 1.0, "m": 1.0, "millimeter": 1e-3, "millimeters": 1e-3, "mm": 1e-3,
               "centimeter": 1e-2, "cm": 1e-2, "inch": 0.0254, "in": 0.0254},
    "FORCE": {"newton": 1.0, "n": 1.0, "kilonewton": 1e3, "kn": 1e3, "pound_force": 4.4482216152605,
              "lbf": 4.4482216152605},
    "PRESSURE": {"pascal": 1.0, "pa": 1.0, "kilopascal": 1e3, "kpa": 1e3, "bar": 1e5,
                 "megapascal": 1e6, "mpa": 1e6, "psi": 6894.757293168361},
    "ANGLE": {"radian": 1.0, "radians": 1.0, "rad": 1.0, "degree": math.pi / 180.0,
              "degrees": math.pi / 180.0, "deg": math.pi / 180.0},
    "MASS": {"kg": 1.0, "kilogram": 1.0, "kilograms": 1.0, "gram": 1e-3, "g": 1e-3, "tonne": 1e3},
    "TIME": {"second": 1.0, "seconds": 1.0, "sec": 1.0, "s": 1.0, "millisecond": 1e-3, "ms": 1e-3},
}  # fmt: skip
"""SI factor of each unit name a [UNITS] entry may give, per quantity (names case-insensitive)."""

_SI_DEFAULT = {"LENGTH": "meter", "FORCE": "newton", "ANGLE": "radian", "MASS": "kg", "TIME": "second"}

_SECTION = re.compile(r"^\[\s*([A-Za-z0-9_]+)\s*\]$")
_ENTRY = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)\s*=\s*(.*)$")


@dataclass(frozen=True)
class _Value:
    text: str  # as written, quotes removed
    quoted: bool
    line: int


@dataclass(frozen=True)
class TirFile:
    """A parsed tyre property file: raw values by section and key, with their line numbers.

    Attributes
    ----------
    path : Path
        The file read (named in every error message).
    sections : dict
        ``{SECTION: {KEY: value}}``, names upper-case; values as written (quotes removed).
    tables : dict
        ``{SECTION: [[float, ...], ...]}``, rows of the table blocks (``{...}`` headers).
    """

    path: Path
    sections: dict[str, dict[str, _Value]]
    tables: dict[str, list[list[float]]] = field(default_factory=dict)

    def has(self, section: str, key: str) -> bool:
        """Whether ``[section] key`` is given."""
        return key.upper() in self.sections.get(section.upper(), {})

    def _entry(self, section: str, key: str) -> _Value:
        entries = self.sections.get(section.upper())
        if entries is None:
            raise InputError(f"tyre file {self.path}: section [{section.upper()}] missing (needed for {key})")
        if key.upper() not in entries:
            raise InputError(f"tyre file {self.path}: [{section.upper()}] lacks the key {key.upper()}")
        return entries[key.upper()]

    def text(self, section: str, key: str) -> str:
        """The value of ``[section] key`` as written (a string entry such as a unit name)."""
        return self._entry(section, key).text

    def number(
        self, section: str, key: str, dimension: str = "", *, greater_than: float | None = None,
        at_least: float | None = None,
    ) -> float:
        """The value of ``[section] key`` in SI units.

        Parameters
        ----------
        section, key : str
            Where the value stands (case-insensitive).
        dimension : str
            Its dimension as a product/quotient of LENGTH, FORCE, PRESSURE, ANGLE, MASS,
            TIME (case-insensitive, e.g. ``"force/length"``, ``"force*time/length"``);
            ``""`` (default) for a dimensionless coefficient.
        greater_than, at_least : float, optional
            The allowed range of the value in SI units (``value > greater_than``,
            ``value >= at_least``); default: any finite number.

        Raises
        ------
        InputError
            If the key is missing, the value is not a finite number or outside its range,
            or a unit it needs is not one this reader knows.
        """
        entry = self._entry(section, key)
        where = f"tyre file {self.path}, line {entry.line}: [{section.upper()}] {key.upper()}"
        try:
            value = float(entry.text)
        except ValueError:
            value = math.nan
        if entry.quoted or not math.isfinite(value):
            raise InputError(f"{where} must be a finite number, got {entry.text!r}")
        value *= self._scale(dimension)
        if greater_than is not None and not value > greater_than:
            raise InputError(f"{where} must be > {greater_than:g} (SI), got {entry.text}")
        if at_least is not None and not value >= at_least:
            raise InputError(f"{where} must be ≥ {at_least:g} (SI), got {entry.text}")
        return value

    def _scale(self, dimension: str) -> float:
        scale = 1.0
        for power, name in re.findall(r"([*/]?)\s*([A-Za-z]+)", dimension):
            factor = self._unit_factor(name.upper())
            scale = scale / factor if power == "/" else scale * factor
        return scale

    def _unit_factor(self, quantity: str) -> float:
        if quantity not in _UNIT_FACTORS:
            raise ValueError(f"unknown dimension {quantity!r}")  # a programming error, not the file's
        units = self.sections.get("UNITS", {})
        if quantity == "PRESSURE" and "PRESSURE" not in units:
            return self._unit_factor("FORCE") / self._unit_factor("LENGTH") ** 2
        entry = units.get(quantity)
        name = _SI_DEFAULT[quantity] if entry is None else entry.text
        factor = _UNIT_FACTORS[quantity].get(name.strip().lower())
        if factor is None:
            line = "" if entry is None else f", line {entry.line}"
            raise InputError(
                f"tyre file {self.path}{line}: [UNITS] {quantity} = {name!r} is not a unit this reader "
                f"knows; expected one of {', '.join(_UNIT_FACTORS[quantity])}"
            )
        return factor


def _split_comment(text: str) -> str:
    """`text` up to the first ``$`` that is not inside quotes."""
    quote = None
    for i, char in enumerate(text):
        if quote:
            if char == quote:
                quote = None
        elif char in "'\"":
            quote = char
        elif char == "$":
            return text[:i]
    return text


def read_tir(path: str | Path) -> TirFile:
    """Parse the tyre property file at `path` (see the module docstring for the format).

    Raises
    ------
    InputError
        If the file does not exist or a line is malformed; the message names the file,
        the line number and the key (or the text of the line).
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"tyre file {str(path)!r} does not exist")
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError as error:
        raise InputError(f"tyre file {str(path)!r} cannot be read ({error})") from None
    sections: dict[str, dict[str, _Value]] = {}
    tables: dict[str, list[list[float]]] = {}
    section = None
    in_table = False
    for number, raw in enumerate(lines, start=1):
        stripped = raw.strip()
        if not stripped or stripped[0] in "$!":
            continue
        line = _split_comment(stripped).strip()
        if not line:
            continue
        match = _SECTION.match(line)
        if match:
            section = match.group(1).upper()
            sections.setdefault(section, {})
            in_table = False
            continue
        where = f"tyre file {path}, line {number}"
        if line.startswith("{"):
            if section is None:
                raise InputError(f"{where}: a table {line!r} before any [SECTION]")
            in_table = True
            tables.setdefault(section, [])
            continue
        match = _ENTRY.match(line)
        if match is None:
            if in_table:
                try:
                    tables[section].append([float(v) for v in line.split()])
                    continue
                except ValueError:
                    pass
            raise InputError(f"{where}: expected KEY = value, got {stripped!r}")
        key, value = match.group(1).upper(), match.group(2).strip()
        if section is None:
            raise InputError(f"{where}: {key} stands before any [SECTION]")
        quoted = len(value) >= 2 and value[0] == value[-1] and value[0] in "'\""
        if quoted:
            value = value[1:-1]
        elif not value or value[0] in "'\"":
            raise InputError(f"{where}: [{section}] {key} has no value or an unclosed quote: {stripped!r}")
        if key in sections[section]:
            first = sections[section][key].line
            raise InputError(f"{where}: [{section}] {key} is given twice (first on line {first})")
        sections[section][key] = _Value(value, quoted, number)
    return TirFile(path=path, sections=sections, tables=tables)

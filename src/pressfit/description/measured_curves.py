"""Measured force-displacement curves: a press monitor's CSV exports read into SI arrays (docs/monitor.md).

Two layouts, told apart by what precedes the curve table:

* **a plain CSV**: the first line (after ``#`` comments) is the header, then one row per sample;
* **a part protocol** (the part-protocol export of a process monitor): a header block of ``key;value`` lines
  (part number, date, program, result ...), kept as ``MeasuredCurve.header``, then the curve table: a names row,
  an optional units row, one row per sample. The exact layout of a vendor's export is not public in the sources
  this module was written from; this is the documented general structure, so an export whose curve table has
  named columns reads as it is.

The table's header row is the first line that names a displacement and a force column. Its delimiter is ``;`` if
the row holds one (then a decimal comma is read as a point: ``0,125``), else a tab, else ``,``. Columns are found
by name, case-insensitively (:data:`SYNONYMS`: ``Force``, ``Kraft``, ``F``, ``Y``; ``Displacement``, ``Weg``,
``Position``, ``Depth``, ``X``; ``Time``, ``Zeit``, ``t``), an exact name before a name that contains the word
(``force_n`` before ``pin1_force_n``); time is optional. Units come from the header (``Force [kN]``,
``Weg (mm)``, ``force_kn``), from the units row, or from the caller (``units``): s or ms; m, mm or um; N or kN.

Refused with a :class:`~pressfit.errors.CurveFileError` naming the file, the row (line number) and the column:
a file of ``MAX_CURVE_BYTES`` or more (before reading it), no header, a unit that is unknown or missing, a cell
that is not a finite number (NaN, inf, empty), an empty or one-point curve, time running backwards, and a
displacement that runs backwards (by more than ``REVERSAL_TOLERANCE_M``) before its maximum. What follows the
maximum displacement is the return stroke: kept, and ignored by the judging (:attr:`MeasuredCurve.forward_end`).
A press springing back as its force drops (by its compliance times the drop) or a force limiter backing the tool
off records such a step back: the error says by how much and how the force changed, and a larger reversal tolerance
takes it as one forward stroke.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pressfit.errors import CurveFileError

MAX_CURVE_BYTES = 10_000_000  # a file of 10 MB or more is refused before it is read
REVERSAL_TOLERANCE_M = 1e-6  # a displacement may step back this much before its maximum (encoder jitter)
ROLES = ("time", "displacement", "force")
SYNONYMS: dict[str, frozenset[str]] = {
    "time": frozenset({"time", "t", "zeit"}),
    "displacement": frozenset({"displacement", "position", "distance", "depth", "stroke", "travel", "weg", "x",
                               "pos", "deflection"}),
    "force": frozenset({"force", "kraft", "f", "y", "load"}),
}
UNITS: dict[str, dict[str, float]] = {  # factor to SI, keys lower case
    "time": {"s": 1.0, "ms": 1e-3},
    "displacement": {"m": 1.0, "mm": 1e-3, "um": 1e-6, "\u00b5m": 1e-6, "\u03bcm": 1e-6},
    "force": {"n": 1.0, "kn": 1e3},
}
_BRACKET = re.compile(r"^(.*?)[\[(]\s*([^\])]*?)\s*[\])]\s*$")


@dataclass(frozen=True, kw_only=True)
class MeasuredCurve:
    """One measured curve in SI: ``displacement_m`` (m), ``force_n`` (N), ``time_s`` (s, or None without a time
    column), one value per sample; ``lines`` the file's line number of each sample; ``forward_end`` the index of
    the maximum displacement (samples after it are the return stroke); ``name`` the part's id (a part protocol's
    part number or serial key, else the file's stem); ``layout`` ``"csv"`` or ``"part_protocol"``; ``header`` the
    part protocol's key-value block; ``columns`` role -> the column's name in the file."""

    path: str
    name: str
    layout: str
    displacement_m: np.ndarray
    force_n: np.ndarray
    time_s: np.ndarray | None
    lines: np.ndarray
    forward_end: int
    header: dict[str, str] = field(default_factory=dict)
    columns: dict[str, str] = field(default_factory=dict)

    def forward(self) -> tuple[np.ndarray, np.ndarray]:
        """The forward stroke (displacement m, force N): the samples up to the maximum displacement."""
        k = self.forward_end + 1
        return self.displacement_m[:k], self.force_n[:k]


def _read_text(path: Path) -> str:
    try:
        if not path.is_file():
            raise CurveFileError(path, None, None, "file does not exist (or is not a regular file)")
        size = path.stat().st_size
        if size >= MAX_CURVE_BYTES:
            raise CurveFileError(path, None, None, f"{size} bytes: a curve file must be smaller than "
                                 f"{MAX_CURVE_BYTES} bytes (not read)")
        raw = path.read_bytes()
    except OSError as exc:
        raise CurveFileError(path, None, None, f"cannot read it ({exc.strerror})") from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        return raw.decode("cp1252", errors="replace")  # a Windows export (e.g. "Weg [\xb5m]")


def _delimiter(line: str) -> str:
    return ";" if ";" in line else "\t" if "\t" in line else ","


def _split(line: str, delimiter: str) -> list[str]:
    return [c.strip().strip('"').strip() for c in line.split(delimiter)]


def _words(name: str) -> list[str]:
    return [w for w in re.split(r"[^0-9a-z\u00b5\u03bc]+", name.lower()) if w]


def _name_and_unit(cell: str) -> tuple[str, str | None]:
    """``Force [kN]`` -> ("force", "kN"); ``Weg (mm)`` -> ("weg", "mm"); ``force_kn`` -> ("force", "kn");
    ``X`` -> ("x", None)."""
    m = _BRACKET.match(cell)
    if m:
        return m.group(1).strip().lower(), m.group(2).strip()
    low = cell.strip().lower()
    head, sep, tail = low.rpartition("_")
    if sep and head and any(tail in u for u in UNITS.values()):
        return head, tail
    return low, None


def _role_of(name: str) -> tuple[str, int] | None:
    """(role, rank) of a column name: rank 0 an exact synonym, 1 a name containing one as a word."""
    for role in ROLES:
        if name in SYNONYMS[role] or name.replace(" ", "_") in SYNONYMS[role]:
            return role, 0
    words = _words(name)
    for role in ("displacement", "force", "time"):  # "press force" before "t"
        if any(w in SYNONYMS[role] for w in words if len(w) > 1):
            return role, 1
    return None


def _header_roles(cells: list[str]) -> dict[str, list[tuple[int, int]]]:
    """role -> [(rank, column index)] of a candidate header row."""
    found: dict[str, list[tuple[int, int]]] = {r: [] for r in ROLES}
    for j, cell in enumerate(cells):
        hit = _role_of(_name_and_unit(cell)[0])
        if hit is not None:
            found[hit[0]].append((hit[1], j))
    return found


def _is_number(cell: str) -> bool:
    try:
        float(cell.replace(",", "."))
    except ValueError:
        return False
    return True


def _pick(path: Path, line: int, cells: list[str], role: str, hits: list[tuple[int, int]],
          wanted: str | None) -> int | None:
    if wanted is not None:
        for j, c in enumerate(cells):
            if c.lower() == wanted.lower() or _name_and_unit(c)[0] == wanted.lower():
                return j
        raise CurveFileError(path, line, wanted, f"no {role} column of this name in the header "
                             f"({', '.join(cells)})")
    if not hits:
        return None
    best = min(r for r, _ in hits)
    tied = [j for r, j in hits if r == best]
    if len(tied) > 1:
        names = " and ".join(repr(cells[j]) for j in tied)
        raise CurveFileError(path, line, cells[tied[1]], f"two {role} columns, {names}: name the one to read "
                             f"(--{role}-column)")
    return tied[0]


def _unit(path: Path, line: int, column: str, role: str, text: str | None, given: str | None) -> float:
    unit = text if text else given
    if not unit:
        raise CurveFileError(path, line, column, f"no unit for the {role}: write it in the header "
                             f"('{column} [{next(iter(UNITS[role]))}]') or give it (--{role}-unit)")
    factor = UNITS[role].get(unit.strip().lower())
    if factor is None:
        raise CurveFileError(path, line, column, f"unknown {role} unit {unit!r} (known: "
                             f"{', '.join(u for u in UNITS[role] if u.isascii())})")
    return factor


def _number(path: Path, line: int, column: str, cell: str, decimal_comma: bool) -> float:
    text = cell.replace(",", ".") if decimal_comma and "." not in cell else cell
    try:
        v = float(text)
    except ValueError:
        raise CurveFileError(path, line, column, f"{cell!r} is not a number") from None
    if not math.isfinite(v):
        raise CurveFileError(path, line, column, f"{cell!r} is not a finite number")
    return v


def _header_row(path: Path, numbered: list[tuple[int, str]], columns: dict[str, str]) -> int:
    """The index in ``numbered`` (line number, text) of the header row: the first row not a comment that names a
    displacement and a force column (or the ``columns`` asked for) and is not all numbers; CurveFileError if none."""
    for k, (_, line) in enumerate(numbered):
        if line.lstrip().startswith("#"):
            continue
        cells = _split(line, _delimiter(line))
        roles = _header_roles(cells)
        wanted = all(columns.get(r) is None or any(c.lower() == columns[r].lower()
                                                     or _name_and_unit(c)[0] == columns[r].lower() for c in cells)
                     for r in ("displacement", "force"))
        if (roles["displacement"] or columns.get("displacement")) and (roles["force"] or columns.get("force")) \
                and wanted and not all(_is_number(c) for c in cells if c):
            return k
    raise CurveFileError(path, numbered[0][0] if numbered else None, None, "no header row naming a displacement "
                         "and a force column (e.g. 'Displacement [mm];Force [kN]')")


def _forward_end(path: Path, x: np.ndarray, force: np.ndarray, line_no: np.ndarray, column: str,
                 tolerance_m: float) -> int:
    """The index of the forward stroke's end (the maximum displacement), or CurveFileError where the displacement
    runs backwards before it by more than ``tolerance_m`` (m), naming the row, by how much and the force's change."""
    end = int(np.argmax(x))
    ahead = np.maximum.accumulate(x[:end + 1])
    back = np.flatnonzero(x[:end + 1] < ahead - tolerance_m)
    if back.size:
        k = int(back[0])
        top = int(np.flatnonzero(x[:k] == ahead[k])[0])
        raise CurveFileError(path, int(line_no[k]), column,
                             f"the displacement runs backwards by {ahead[k] - x[k]:.4g} m (row {int(line_no[top])} "
                             f"to this one, the force {force[top]:.6g} N to {force[k]:.6g} N) before its maximum at "
                             f"row {int(line_no[end])}, more than the reversal tolerance {tolerance_m:g} m: only a "
                             "return stroke after the maximum is allowed (a press springing back as its force drops, "
                             "or a limiter backing the tool off, records such a step: allow a larger reversal "
                             "tolerance to take it as one forward stroke)")
    return end


def read_curve(path: Path | str, *, units: dict[str, str] | None = None, columns: dict[str, str] | None = None,
               reversal_tolerance_m: float = REVERSAL_TOLERANCE_M) -> MeasuredCurve:
    """Read and check one measured curve (module doc). ``units``: role -> unit for columns whose header names
    none (``{"force": "kN"}``; a unit in the header wins); ``columns``: role -> the column's name to read where
    the header's names are ambiguous or unusual. Raises CurveFileError (file, row, column)."""
    path = Path(path)
    units, columns = units or {}, columns or {}
    numbered = [(i, line) for i, line in enumerate(_read_text(path).splitlines(), 1) if line.strip()]
    head_at = _header_row(path, numbered, columns)
    before = [(i, line) for i, line in numbered[:head_at] if not line.lstrip().startswith("#")]
    head_line, head_text = numbered[head_at]
    delim = _delimiter(head_text)
    cells = _split(head_text, delim)
    roles = _header_roles(cells)
    index = {r: _pick(path, head_line, cells, r, roles[r], columns.get(r)) for r in ROLES}
    if index["displacement"] is None or index["force"] is None:  # pragma: no cover - the header search ensures it
        raise CurveFileError(path, head_line, None, "no displacement and force columns")
    rows = numbered[head_at + 1:]
    unit_row: list[str] | None = None
    if rows:
        first = _split(rows[0][1], delim)
        used = [first[j] if j < len(first) else "" for j in index.values() if j is not None]
        if used and all(c and not _is_number(c) for c in used):
            unit_row, rows = [u.strip("[]() ") for u in first], rows[1:]
    factor, name = {}, {}
    for role, j in index.items():
        if j is None:
            continue
        name[role] = cells[j]
        text = _name_and_unit(cells[j])[1]
        if text is None and unit_row is not None and j < len(unit_row):
            text = unit_row[j] or None
        factor[role] = _unit(path, head_line, cells[j], role, text, units.get(role))
    decimal_comma = delim != ","
    values: dict[str, list[float]] = {r: [] for r in factor}
    lines = []
    for i, line in rows:
        if line.lstrip().startswith("#"):
            continue
        row = _split(line, delim)
        for role in factor:
            j = index[role]
            if j >= len(row) or not row[j]:  # type: ignore[operator]
                raise CurveFileError(path, i, name[role], f"no value ({len(row)} cells for the header's "
                                     f"{len(cells)})")
            values[role].append(_number(path, i, name[role], row[j], decimal_comma) * factor[role])  # type: ignore
        lines.append(i)
    if len(lines) < 2:
        where = lines[0] if lines else head_line
        raise CurveFileError(path, where, name["displacement"], "an empty curve (no data rows)" if not lines else
                             "a one-point curve: a curve needs at least two points")
    x = np.array(values["displacement"])
    line_no = np.array(lines)
    if "time" in values:
        t = np.array(values["time"])
        back = np.flatnonzero(np.diff(t) < 0)
        if back.size:
            k = back[0] + 1
            raise CurveFileError(path, int(line_no[k]), name["time"], f"time runs backwards ({t[k - 1]:g} s to "
                                 f"{t[k]:g} s)")
    force = np.array(values["force"])
    end = _forward_end(path, x, force, line_no, name["displacement"], reversal_tolerance_m)
    header = {}
    for _, line in before:
        key, _, value = line.partition(delim if delim in line else _delimiter(line))
        header[key.strip().strip('"')] = value.strip().strip('"').strip(delim).strip()
    part = next((header[k] for k in header if _words(k)[:1] in (["part"], ["serial"], ["teil"], ["id"])
                 and header[k]), None)
    return MeasuredCurve(path=str(path), name=part or path.stem, layout="part_protocol" if before else "csv",
                         displacement_m=x, force_n=force,
                         time_s=np.array(values["time"]) if "time" in values else None, lines=line_no,
                         forward_end=end, header=header, columns=name)

"""A built machine's measurements for calibration: the deflection file and the tap-test (modes) file.

Deflections (CSV, one row per pose and load, header required, SI units):
``x_m,y_m,z_m`` the plate-centre pose h, ``fx_n,fy_n,fz_n`` the load at the tool (the plate centre, world axes),
``dx_m,dy_m,dz_m`` the measured tool translation from the unloaded state at that pose; optional
``rx_rad,ry_rad,rz_rad`` (the measured plate rotation; then ``sigma_rad`` is required), ``sigma_m`` (the
per-row standard deviation of each translation component, m) and ``sigma_rad``. Either every row has a sigma
or the column is absent (the fit then estimates the noise from the residuals).
Modes (CSV): ``x_m,y_m,z_m,frequency_hz`` and optional ``sigma_hz``.

Every check names the file, the row (line number, header = 1) and the column: a missing column, a value that
is not a finite number, a pose out of reach (the broken limit), a non-positive sigma, zero load on every row.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pressfit.description.machine import MAX_INPUT_BYTES, Machine
from pressfit.errors import MeasurementFileError
from pressfit.kinematics import unreachable_reason

POSE = ("x_m", "y_m", "z_m")
LOAD = ("fx_n", "fy_n", "fz_n")
TRANSLATION = ("dx_m", "dy_m", "dz_m")
ROTATION = ("rx_rad", "ry_rad", "rz_rad")
FREQUENCY = ("frequency_hz",)


@dataclass(frozen=True, kw_only=True)
class Deflections:
    """Measured deflections, m rows (SI): arrays (m, 3); ``rotation_rad`` None without rotation columns;
    ``sigma_m`` / ``sigma_rad`` (m,) or None; ``lines`` the file's line number of each row."""

    path: str
    pose_m: np.ndarray
    load_n: np.ndarray
    translation_m: np.ndarray
    rotation_rad: np.ndarray | None
    sigma_m: np.ndarray | None
    sigma_rad: np.ndarray | None
    lines: np.ndarray

    @property
    def components(self) -> int:
        """Measured numbers per row: 3 translations, plus 3 rotations when given."""
        return 3 if self.rotation_rad is None else 6


@dataclass(frozen=True, kw_only=True)
class Frequencies:
    """Measured first natural frequencies (k rows): ``pose_m`` (k, 3) m, ``frequency_hz`` (k,), ``sigma_hz``
    (k,) or None, ``lines`` the file's line numbers."""

    path: str
    pose_m: np.ndarray
    frequency_hz: np.ndarray
    sigma_hz: np.ndarray | None
    lines: np.ndarray


def _read_rows(path: Path | str, required: tuple[str, ...]) -> tuple[list[str], list[tuple[int, dict[str, str]]]]:
    path = Path(path)
    try:
        if not path.is_file():
            raise MeasurementFileError(path, None, None, "file does not exist (or is not a regular file)")
        if path.stat().st_size > MAX_INPUT_BYTES:
            raise MeasurementFileError(path, None, None, f"larger than {MAX_INPUT_BYTES} bytes: not a measurement file")
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise MeasurementFileError(path, None, None, "not a UTF-8 text file") from None
    except OSError as exc:
        raise MeasurementFileError(path, None, None, f"cannot read it ({exc.strerror})") from None
    lines = [(i, line) for i, line in enumerate(text.splitlines(), 1) if line.strip() and not line.startswith("#")]
    if not lines:
        raise MeasurementFileError(path, None, None, "no header and no rows")
    header = [h.strip() for h in next(csv.reader([lines[0][1]]))]
    for col in required:
        if col not in header:
            raise MeasurementFileError(path, lines[0][0], col,
                                       f"missing column (the header needs {','.join(required)})")
    rows = []
    for i, line in lines[1:]:
        cells = [c.strip() for c in next(csv.reader([line]))]
        if len(cells) != len(header):
            raise MeasurementFileError(path, i, None, f"{len(cells)} values for {len(header)} columns")
        rows.append((i, dict(zip(header, cells, strict=True))))
    if not rows:
        raise MeasurementFileError(path, None, None, "a header but no measurement rows")
    return header, rows


def _column(path: Path | str, rows: list[tuple[int, dict[str, str]]], name: str, positive: bool = False) -> np.ndarray:
    out = np.empty(len(rows))
    for k, (i, row) in enumerate(rows):
        try:
            v = float(row[name])
        except ValueError:
            raise MeasurementFileError(path, i, name, f"{row[name]!r} is not a number") from None
        if not math.isfinite(v):
            raise MeasurementFileError(path, i, name, f"{row[name]!r} is not a finite number")
        if positive and not v > 0:
            raise MeasurementFileError(path, i, name, f"{v:g} must be positive")
        out[k] = v
    return out


def _block(path: Path | str, rows: list[tuple[int, dict[str, str]]], names: tuple[str, ...]) -> np.ndarray:
    return np.stack([_column(path, rows, n) for n in names], -1)


def _reachable_poses(machine: Machine, path: Path | str, rows: list[tuple[int, dict[str, str]]]) -> np.ndarray:
    poses = _block(path, rows, POSE)
    for (i, _), h in zip(rows, poses, strict=True):
        reason = unreachable_reason(machine, h)
        if reason:
            raise MeasurementFileError(path, i, ",".join(POSE), f"pose {tuple(h.tolist())} m is out of reach: {reason}")
    return poses


def _optional(path: Path | str, header: list[str], rows: list[tuple[int, dict[str, str]]],
              name: str) -> np.ndarray | None:
    return _column(path, rows, name, positive=True) if name in header else None


def read_deflections(machine: Machine, path: Path | str) -> Deflections:
    """Read and check a deflection file (module doc); raises MeasurementFileError naming file, row, column."""
    header, rows = _read_rows(path, POSE + LOAD + TRANSLATION)
    poses = _reachable_poses(machine, path, rows)
    loads = _block(path, rows, LOAD)
    if not np.any(loads):
        raise MeasurementFileError(path, None, ",".join(LOAD), "the load is zero on every row: no deflection "
                                   "measured under a load, nothing to fit")
    has_rotation = [c for c in ROTATION if c in header]
    if has_rotation and len(has_rotation) != 3:
        missing = next(c for c in ROTATION if c not in header)
        raise MeasurementFileError(path, None, missing, "rotation columns come as all three or none")
    rotation = _block(path, rows, ROTATION) if has_rotation else None
    sigma_rad = _optional(path, header, rows, "sigma_rad")
    if rotation is not None and sigma_rad is None:
        raise MeasurementFileError(path, None, "sigma_rad", "rotation columns need a sigma_rad column "
                                   "(the weights of rotations against translations)")
    sigma_m = _optional(path, header, rows, "sigma_m")
    if rotation is not None and sigma_m is None:
        raise MeasurementFileError(path, None, "sigma_m", "rotation columns need a sigma_m column too")
    return Deflections(path=str(path), pose_m=poses, load_n=loads, translation_m=_block(path, rows, TRANSLATION),
                       rotation_rad=rotation, sigma_m=sigma_m, sigma_rad=sigma_rad,
                       lines=np.array([i for i, _ in rows]))


def read_frequencies(machine: Machine, path: Path | str) -> Frequencies:
    """Read and check a modes file (module doc): the first natural frequency measured at each pose."""
    header, rows = _read_rows(path, POSE + FREQUENCY)
    return Frequencies(path=str(path), pose_m=_reachable_poses(machine, path, rows),
                       frequency_hz=_column(path, rows, "frequency_hz", positive=True),
                       sigma_hz=_optional(path, header, rows, "sigma_hz"), lines=np.array([i for i, _ in rows]))

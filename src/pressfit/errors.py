"""The package's exceptions: every failure a user can cause derives from :class:`PressfitError`."""

from __future__ import annotations

from collections.abc import Iterable


class PressfitError(Exception):
    """Base class of every error pressfit raises on purpose (the CLI turns it into exit code 2)."""


class ModelFileError(PressfitError):
    """A machine or case file is malformed: names the file, the key and what was expected."""

    def __init__(self, path: object, key: str, expected: str) -> None:
        self.path, self.key, self.expected = str(path), key, expected
        super().__init__(f"{self.path}: key '{key}': {expected}")


class WrongFileKindError(PressfitError):
    """A file of one kind given where another is read (a machine file as a case, a case as a machine): ``path``,
    ``kind`` (what the file is: "machine", "case") and ``expected`` (what was read)."""

    HOW = {"machine": "give it with --model (or as a case file's model key)",
           "case": "give it where a case file is read (a command's CASE argument)"}

    def __init__(self, path: object, kind: str, expected: str) -> None:
        self.path, self.kind, self.expected = str(path), kind, expected
        super().__init__(f"{self.path} is a {kind} file, not a {expected} file: {self.HOW.get(kind, '')}".rstrip(": "))


def format_violation(leg: int, quantity: str, value: float, limit: str) -> str:
    """The one text of a broken limit: "leg 2: alpha [rad] = 1.57081 breaks maximum 1.5708" (no "leg"
    part for leg 0, a pose-wide limit). ``limit`` is "<minimum|maximum> <number>[ ...]"; the value gets
    6 significant digits, or as many more as it takes for the printed value to break the printed limit
    (a value just above a maximum never reads as equal to it)."""
    kind, _, rest = limit.partition(" ")
    try:
        bound = float(rest.split()[0])
    except (ValueError, IndexError):
        bound = None
    for digits in range(6, 18):
        text = f"{value:.{digits}g}"
        if bound is None or (float(text) > bound if kind == "maximum" else float(text) < bound):
            break
    return (f"leg {leg}: " if leg else "") + f"{quantity} = {text} breaks {limit}"


class UnreachablePoseError(PressfitError):
    """A plate pose breaks a joint limit; ``violations`` lists (leg, quantity, value, limit)."""

    def __init__(self, pose_m: tuple[float, ...], violations: list[tuple[int, str, float, str]]) -> None:
        self.pose_m, self.violations = pose_m, violations
        pose = tuple(float(c) for c in pose_m)
        super().__init__(f"pose {pose} m is not reachable: " + "; ".join(format_violation(*v) for v in violations))


def _floats(values: Iterable[float] | None) -> tuple[float, ...] | None:
    """A pose or a wrench as a tuple of floats (None stays None)."""
    return None if values is None else tuple(float(v) for v in values)


class SingularPoseError(PressfitError):
    """The static matrix or the stiffness is singular at this pose: ``pose_m`` the plate pose (m; the first
    singular pose of a batch), ``smallest_singular_value`` and ``determinant`` of the matrix the message names
    (in that matrix's units; det(A A^T) is dimensionless); each None where the raiser does not have it."""

    def __init__(self, message: str, *, pose_m: Iterable[float] | None = None,
                 smallest_singular_value: float | None = None, determinant: float | None = None) -> None:
        self.pose_m, self.determinant = _floats(pose_m), determinant
        self.smallest_singular_value = smallest_singular_value
        super().__init__(message)


class ConvergenceError(PressfitError):
    """An iterative solver stopped before meeting its tolerance; carries the residual reached."""

    def __init__(self, what: str, residual: float, tolerance: float, iterations: int) -> None:
        self.residual, self.tolerance, self.iterations = residual, tolerance, iterations
        super().__init__(
            f"{what} did not converge: residual {residual:.3e} > tolerance {tolerance:.1e} "
            f"after {iterations} iterations"
        )


class OutputExistsError(PressfitError):
    """An output file exists and overwriting was not requested (or another run holds it): ``path`` the file
    or directory refused."""

    def __init__(self, message: str, *, path: object) -> None:
        self.path = str(path)
        super().__init__(message)


class OutputError(PressfitError):
    """An output file cannot be written (its directory is a file, or not writable): ``path`` the output
    refused (None when the request itself is wrong, before any path)."""

    def __init__(self, message: str, *, path: object = None) -> None:
        self.path = None if path is None else str(path)
        super().__init__(message)


class OutputConflictError(OutputError):
    """Two output options name one file, or an output is one of the command's input files: ``option`` and
    ``path`` the output, ``other`` the other option or the input (refused before any computation)."""

    def __init__(self, option: str, path: object, other: str, message: str) -> None:
        self.option, self.other = option, other
        super().__init__(message, path=path)


class ResidualError(PressfitError):
    """A solver returned a solution whose residual exceeds the stated tolerance (the answer is not trusted):
    ``residual`` names it, ``value`` and ``tolerance`` are relative (the solver's definitions)."""

    def __init__(self, what: str, residual: str, value: float, tolerance: float, where: str = "") -> None:
        self.what, self.residual, self.value, self.tolerance, self.where = what, residual, value, tolerance, where
        super().__init__(f"{what}{' ' + where if where else ''}: residual {residual} = {value:.3e} exceeds its "
                         f"tolerance {tolerance:.1e}; the solution is refused")


class PreloadError(PressfitError):
    """A preload that cannot be applied (unknown mode, non-finite amplitude, a machine without redundancy or
    with another number of preload amplitudes): ``machine`` names the machine (or "" if unknown),
    ``redundancy`` its degree n - 3 (None if unknown)."""

    def __init__(self, message: str, machine: str = "", redundancy: int | None = None) -> None:
        self.machine, self.redundancy = machine, redundancy
        super().__init__(f"{machine}: {message}" if machine else message)


class CasePreloadError(PreloadError):
    """A case file's ``[preload]`` that does not fit its machine's leg count: ``path`` the case file, ``key`` the
    preload key (``[preload] a4_n``, ...), ``machine`` and ``redundancy`` as :class:`PreloadError`."""

    def __init__(self, path: object, key: str, message: str, machine: str, redundancy: int) -> None:
        super().__init__(message, machine, redundancy)
        self.path, self.key = str(path), key
        self.args = (f"{self.path}: key '{key}': {message}",)

    def __str__(self) -> str:
        return str(self.args[0])


class LegCountError(PressfitError):
    """A layer that supports only some numbers of legs got a machine with another: ``machine`` its name,
    ``legs`` its leg count, ``supported`` the counts the layer takes, ``layer`` the layer's name."""

    def __init__(self, machine: str, legs: int, supported: tuple[int, ...], layer: str) -> None:
        self.machine, self.legs, self.supported, self.layer = machine, legs, supported, layer
        counts = " or ".join(str(n) for n in supported)
        super().__init__(f"{machine}: {layer} supports {counts}-leg machines only so far; this machine has {legs} legs")


class UnstableEquilibriumError(PressfitError):
    """The solution found is not a physical, stable state (a leg beyond buckling, a huge displacement):
    ``leg`` the leg at fault (1-n; None: the whole machine), ``pose_m`` the plate (or tool) pose (m) and
    ``load`` the wrench applied there (N, N m); each None where the raiser does not have it."""

    def __init__(self, message: str, *, leg: int | None = None, pose_m: Iterable[float] | None = None,
                 load: Iterable[float] | None = None) -> None:
        self.leg, self.pose_m, self.load = leg, _floats(pose_m), _floats(load)
        super().__init__(message)


class DriveStepError(PressfitError):
    """A drive cannot integrate a step (:mod:`pressfit.dynamics.drives`); carries the drive kind, the leg
    (1-n), the quantity, its value and the limit it breaks (SI)."""

    def __init__(self, kind: str, leg: int, quantity: str, value: float, limit: str) -> None:
        self.kind, self.leg, self.quantity, self.value, self.limit = kind, leg, quantity, value, limit
        super().__init__(f"{kind} drive of leg {leg}: {quantity} = {value:.10g} breaks {limit}")


class InterferenceError(PressfitError):
    """Bad interference input (:mod:`pressfit.geometry.interference`): ``key`` the input at fault ("rig",
    "mesh", "pair", "extra_bodies", "probe_poses", "poses"), ``value`` its value (the rig's name, the mesh
    file, the pair 'a|b', the clashing names, the number of reachable probe poses, the number of poses given)
    and ``allowed`` the valid values where there is a list (the rig names, the bodies a pair may name)."""

    def __init__(self, message: str, *, key: str, value: object, allowed: tuple[str, ...] = ()) -> None:
        self.key, self.value, self.allowed = key, value, allowed
        super().__init__(message)


class ClusterError(PressfitError):
    """The Dask cluster cannot be started or reached, or a chunk failed on it (:mod:`pressfit.studies.distributed`):
    ``scheduler`` the address asked for (None: a local cluster), ``workers`` the number of workers asked for
    (None: the default), ``chunk`` the index of the chunk that failed (None: no chunk ran) and ``cause`` the
    underlying error's text ("" if none)."""

    def __init__(self, message: str, *, scheduler: str | None = None, workers: int | None = None,
                 chunk: int | None = None, cause: str = "") -> None:
        self.scheduler, self.workers, self.chunk, self.cause = scheduler, workers, chunk, cause
        super().__init__(message)


class StudyFailedError(PressfitError):
    """Every sample (or design) of a study failed: nothing to summarise; ``failed`` counts the reasons."""

    def __init__(self, what: str, failed: dict[str, int]) -> None:
        self.failed = failed
        reasons = ", ".join(f"{n} x {reason}" for reason, n in sorted(failed.items(), key=lambda t: -t[1]))
        super().__init__(f"{what}: every sample failed ({reasons}); nothing to summarise")


class ClearanceError(PressfitError):
    """Bad clearance or preload input (negative gap, unknown mode, no closing preload found, ...): ``key`` the
    input at fault (an argument or a case file's key, None where the message names no single one), ``path``
    the case file (None: not from a file)."""

    def __init__(self, message: str, *, key: str | None = None, path: object = None) -> None:
        self.key, self.path = key, None if path is None else str(path)
        super().__init__(message)


class FastSolverError(PressfitError):
    """The model has something the fast solver (:mod:`pressfit.mechanics.fast_statics`) does not support: use
    the reference solver."""


class CondensedModelError(PressfitError):
    """The machine breaks an assumption of the condensed model (:mod:`pressfit.mechanics.condensed`): ``machine``
    its name, ``assumption`` the one broken ("concurrent legs", "parallel cardan axes", "free cardans"),
    ``reason`` what in the machine breaks it; the remedy is the Pinocchio statics."""

    def __init__(self, machine: str, assumption: str, reason: str) -> None:
        self.machine, self.assumption, self.reason = machine, assumption, reason
        super().__init__(f"{machine}: {reason}; the condensed model assumes {assumption}: use "
                         "pressfit.mechanics.statics")


class WorkspaceError(PressfitError):
    """The required square, turned by ``angle_deg``, is reachable at no height (``heights_m`` empty) or at heights
    ``heights_m`` (m, the scan's) that do not form one interval."""

    def __init__(self, angle_deg: float, heights_m: list[float], scan_step_m: float) -> None:
        self.angle_deg, self.heights_m, self.scan_step_m = angle_deg, heights_m, scan_step_m
        super().__init__(f"the required square rotated by {angle_deg:g} deg is reachable at no height (scanned y "
                         f"in steps of {scan_step_m:g} m)" if not heights_m else
                         f"the heights where the square rotated by {angle_deg:g} deg is reachable do not form one "
                         f"interval: {heights_m} m")


class MeasurementFileError(PressfitError):
    """A calibration measurement file (or one of its rows) is unusable: ``path``, ``row`` (the 1-based line
    number in the file, header = 1; None for the whole file), ``column`` (a column name, or None) and
    ``reason``."""

    def __init__(self, path: object, row: int | None, column: str | None, reason: str) -> None:
        self.path, self.row, self.column, self.reason = str(path), row, column, reason
        where = ", ".join(([f"row {row}"] if row is not None else []) + ([f"column '{column}'"] if column else []))
        super().__init__(f"{self.path}: {where + ': ' if where else ''}{reason}")


class CalibrationError(PressfitError):
    """A calibration fit failed: ``what`` happened, ``residual`` the last weighted residual norm reached
    (dimensionless when sigma is given, else m), ``keys`` the fitted keys."""

    def __init__(self, what: str, *, residual: float, keys: Iterable[str]) -> None:
        self.what, self.residual, self.keys = what, float(residual), tuple(keys)
        super().__init__(f"calibration of {', '.join(self.keys)} {what} (last residual norm {self.residual:.4g})")


class PressCurveError(PressfitError):
    """The predicted press curve cannot be drawn for a case: ``path`` (the case file, or ""), ``key`` (the key
    that decides it) and ``reason``."""

    def __init__(self, path: object, key: str, reason: str) -> None:
        self.path, self.key, self.reason = str(path), key, reason
        super().__init__(f"{self.path or '<contact>'}: key '{key}': {reason}")


class CurveFileError(MeasurementFileError):
    """A measured force-displacement curve file (:mod:`pressfit.description.measured_curves`) is unusable:
    ``path``, ``row`` (the 1-based line number in the file; None for the whole file), ``column`` (the column's
    name as the file spells it, or None) and ``reason``, as :class:`MeasurementFileError`."""

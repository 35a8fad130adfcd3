"""Residuals are enforced, not only reported (issue 18): a solution whose relative residual exceeds the
stated tolerance is refused by the solver itself (ResidualError naming the residual, value and tolerance;
exit 2 in the CLI), so every caller (solve, check, report, studies) gets the refusal.

Each solver is corrupted just before its residuals are computed: one leg's force on the plate is moved by
delta * F_ref, so the plate force residual |F + sum of the leg forces| / F_ref becomes delta to within the
solve's own residual (measured below 1e-10; the margins here are 5e-11), while the moment residuals change
by at most delta |d_i| / L_ref (a quarter of delta: the plate cardan arm against the base half-side; the fast
solver's whole-machine moment not at all, the shift being along the cardan's position vector). delta just
over the tolerance must be refused, just under accepted."""

import numpy as np
import pytest
from click.testing import CliRunner

import pressfit.mechanics.condensed as condensed
import pressfit.mechanics.fast_statics as fast_statics
import pressfit.mechanics.statics as statics
from pressfit.cli import main
from pressfit.description.machine import DEFAULT_MODEL, load_machine
from pressfit.errors import ResidualError

POSE, LOAD = [0.1, 0.65, -0.05], [20.0, 700.0, -30.0, 0.0, 0.0, 0.0]
OVER, UNDER = 1.05, 0.95  # delta / tolerance


@pytest.fixture(scope="module")
def machine():
    return load_machine(DEFAULT_MODEL)


REFERENCE_RESULT, FAST_RESULTS, CONDENSED_CORE = (statics._result, fast_statics.FastEquilibriumSolver._results,
                                                  condensed._solve_core)


def shift_reference(monkeypatch, delta):
    real = REFERENCE_RESULT

    def corrupted(pb, st, lam, *args, **kwargs):
        lam = lam.copy()
        lam[0, 0] += delta * pb.f_ref
        return real(pb, st, lam, *args, **kwargs)

    monkeypatch.setattr(statics, "_result", corrupted)


def test_the_stated_tolerance():
    assert statics.RESIDUAL_TOL == 1e-9 and statics.residual_tolerance() == 1e-9
    assert statics.residual_tolerance(1e-6) == pytest.approx(1e-5)  # a looser Newton is held to 10 times it


@pytest.mark.parametrize("linear", [False, True])
def test_reference_solver_refuses_a_residual_just_over_the_tolerance(monkeypatch, machine, linear):
    solver = statics.EquilibriumSolver(machine, pose_m=POSE)
    tol = statics.RESIDUAL_TOL
    shift_reference(monkeypatch, OVER * tol)
    with pytest.raises(ResidualError) as err:
        solver.solve(POSE, LOAD, linear=linear)
    e = err.value
    assert e.residual == "plate_force" and e.tolerance == tol
    assert e.value == pytest.approx(OVER * tol, abs=5e-11) and "plate_force" in str(e) and "0.1, 0.65" in str(e)
    shift_reference(monkeypatch, UNDER * tol)
    eq = solver.solve(POSE, LOAD, linear=linear)
    assert eq.residuals.plate_force == pytest.approx(UNDER * tol, abs=5e-11)


def test_a_nan_residual_is_refused():
    rows = np.zeros((2, 7))
    statics.enforce_residuals(rows, 1e-9, "x", str)
    rows[1, 6] = np.nan
    with pytest.raises(ResidualError, match="stationarity = nan") as err:
        statics.enforce_residuals(rows, 1e-9, "x", lambda i: f"sample {i}")
    assert "sample 1" in str(err.value)


def shift_fast(monkeypatch, delta):
    real = FAST_RESULTS

    def corrupted(self, bk, pts, pe, c, r, lam, *args):
        lam = lam.copy()
        lam[:, 0, :3] += delta * bk.f_ref[:, None] * pe[:, 0] / np.linalg.norm(pe[:, 0], axis=-1, keepdims=True)
        return real(self, bk, pts, pe, c, r, lam, *args)

    monkeypatch.setattr(fast_statics.FastEquilibriumSolver, "_results", corrupted)


@pytest.mark.parametrize("linear", [False, True])
def test_fast_solver_refuses_a_residual_just_over_the_tolerance(monkeypatch, machine, linear):
    fast = fast_statics.FastEquilibriumSolver(machine, pose_m=POSE)
    poses = np.array([POSE, [0.0, 0.72, 0.0]])
    shift_fast(monkeypatch, OVER * statics.RESIDUAL_TOL)
    with pytest.raises(ResidualError) as err:
        fast.solve_batch(poses, np.array(LOAD), linear=linear)
    assert err.value.residual == "plate_force" and "fast solver" in str(err.value)
    shift_fast(monkeypatch, UNDER * statics.RESIDUAL_TOL)
    batch = fast.solve_batch(poses, np.array(LOAD), linear=linear)
    assert batch.residuals[:, 0] == pytest.approx(UNDER * statics.RESIDUAL_TOL, abs=5e-11)


def shift_condensed(monkeypatch, delta):
    real = CONDENSED_CORE

    def corrupted(machine, core, w):
        out = list(real(machine, core, w))
        scale = np.linalg.norm(w[:3], axis=0) + np.linalg.norm(w[3:], axis=0)  # relative_residual's scale
        out[7] = out[7] + np.array([1.0, 0.0, 0.0])[:, None] * delta * scale
        return tuple(out)

    monkeypatch.setattr(condensed, "_solve_core", corrupted)


def test_condensed_solve_refuses_a_residual_just_over_its_tolerance(monkeypatch, machine):
    tol = condensed.CONDENSED_RESIDUAL_TOL
    poses = np.array([POSE, [0.0, 0.72, 0.0]])
    shift_condensed(monkeypatch, OVER * tol)
    with pytest.raises(ResidualError) as err:
        condensed.solve_linear(machine, poses, LOAD)
    assert err.value.tolerance == tol and err.value.value == pytest.approx(OVER * tol, rel=0.01)
    shift_condensed(monkeypatch, UNDER * tol)
    res = condensed.solve_linear(machine, poses, LOAD)
    assert res.relative_residual().max() == pytest.approx(UNDER * tol, rel=0.01)


def test_solve_exits_2_naming_the_residual(monkeypatch):
    shift_reference(monkeypatch, OVER * statics.RESIDUAL_TOL)
    res = CliRunner().invoke(main, ["solve", *map(str, POSE), "--load", "20", "700", "-30"])
    assert res.exit_code == 2, (res.output, res.exception)
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: nonlinear equilibrium at pose") and "plate_force" in lines[0]
    assert "exceeds its tolerance 1.0e-09" in lines[0]

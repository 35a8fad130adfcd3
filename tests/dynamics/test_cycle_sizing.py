"""The drive sizing of a whole board (``pressfit cycle``): every figure recomputed here from cycle.csv equals the
JSON's, the preload's share is a4 |v_p,i| along the path (the null-space command, equations 9-10), the energy
balance closes and a balance over its tolerance is refused."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from pressfit import kinematics
from pressfit.cli import main
from pressfit.description.cases import load_case
from pressfit.dynamics import drives, sizing
from pressfit.dynamics.machine.registry import model_kind
from tests.dynamics.test_cycle import board

TWO_PINS = [{"x_m": 0.10, "z_m": -0.05}, {"x_m": 0.0, "z_m": 0.0}]


def run(*args: object):
    return CliRunner().invoke(main, [str(a) for a in args])


def read_csv(path: Path) -> dict[str, np.ndarray]:
    with path.open() as f:
        rows = list(csv.reader(f))
    data = np.array(rows[1:], dtype=float)
    return {name: data[:, k] for k, name in enumerate(rows[0])}


@pytest.fixture(scope="module")
def sized(tmp_path_factory):
    """A two-pin board (0.1 s dwell) written by ``pressfit cycle --out``: its case, CSV columns and JSON."""
    tmp = tmp_path_factory.mktemp("sizing")
    case = board(tmp, pins=TWO_PINS, dwell_s=0.1, settle_s=0.1)
    res = run("cycle", case, "--no-progress", "--out", tmp / "out")
    assert res.exit_code == 0, res.output
    assert "drive sizing (legs 1-4" in res.output and "energy balance: drive work" in res.output, res.output
    for name in ("cycle_drives.png", "cycle_operating_points.png"):
        assert (tmp / "out" / name).stat().st_size > 10_000, name
    return case, read_csv(tmp / "out/cycle.csv"), json.loads((tmp / "out/cycle.json").read_text())


def legs(columns: dict[str, np.ndarray], prefix: str) -> np.ndarray:
    k = 1
    out = []
    while f"{prefix}{k}" in columns:
        out.append(columns[f"{prefix}{k}"])
        k += 1
    return np.column_stack(out)


def test_drive_figures_recomputed_from_the_csv(sized):
    """Peak and RMS force, peak speed, peak power and the energies of each drive from the CSV's tensions and leg
    rates (P = -N l_dot, zero-order hold at dt) equal the JSON's to rounding."""
    _, cols, s = sized
    n, v, dt = legs(cols, "act_n"), legs(cols, "rate_m_per_s"), s["time_step_s"]
    assert len(s["drives"]) == n.shape[1]
    power = -n * v
    for i, d in enumerate(s["drives"]):
        expected = {"peak_force_n": np.abs(n[:, i]).max(), "rms_force_n": np.sqrt(np.mean(n[:, i] ** 2)),
                    "peak_speed_m_per_s": np.abs(v[:, i]).max(), "peak_power_w": max(power[:, i].max(), 0.0),
                    "positive_energy_j": np.clip(power[:, i], 0, None).sum() * dt,
                    "regenerative_energy_j": np.clip(-power[:, i], 0, None).sum() * dt}
        for key, value in expected.items():
            assert d[key] == pytest.approx(value, rel=1e-12, abs=1e-12), (i, key)
        assert d["ratings"]["peak_force_n"]["value"] == pytest.approx(expected["peak_force_n"], rel=1e-12)
        assert d["rms_force_without_preload_n"] != pytest.approx(d["rms_force_n"], rel=0.05)  # the preload costs


def test_preload_share_is_a4_vp_along_the_path(sized):
    """The preload adds a4 v_p (a null-space force: no net wrench on the plate, so the same motion) to every
    command: RMS(N - N_0) of each drive equals a4 RMS(v_p,i) over the plate's path from the CSV, to 1% (the
    estimate and the compliance move the pose by microns; achieved well below 0.5%)."""
    case, cols, s = sized
    a4 = load_case(case).preload.a4_n
    path = np.column_stack([cols["plate_x_m"], cols["plate_y_m"], cols["plate_z_m"]])
    vp = kinematics.preload_vector(load_case(case).machine(), path)
    expected = a4 * np.sqrt(np.mean(vp**2, axis=0))
    share = np.array([d["rms_preload_share_n"] for d in s["drives"]])
    assert share == pytest.approx(expected, rel=0.01)


def _plays_and_stems(cols):
    """The elastic energy change, the plays' stored energy change and dissipation and the sensors' series springs'
    loss less the stems' re-placement energy, J (0 on the rigid model, which the board runs on unless its case says
    otherwise)."""
    return (cols["elastic_energy_j"][-1] - cols["elastic_energy_j"][0]
            + cols["play_energy_j"][-1] - cols["play_energy_j"][0] + cols["play_dissipation_j"][1:].sum()
            + cols["series_loss_j"][1:].sum() - cols["stem_replacement_j"][1:].sum())


def test_energy_balance_closes(sized):
    """The drives' work recomputed from the CSV's lengths and tensions, sum_k -N_k . (l_k - l_k-1), equals the
    JSON's, the terms sum to it with the residual, and the relative residual is within the stated tolerance."""
    _, cols, s = sized
    e = s["energy_balance"]
    n, lengths = legs(cols, "act_n"), legs(cols, "length_m")
    step = np.sum(-n[1:] * np.diff(lengths, axis=0), axis=1)
    assert e["drive_work_j"] == pytest.approx(step.sum(), rel=1e-12)
    assert e["gross_drive_work_j"] == pytest.approx(np.abs(step).sum(), rel=1e-12)
    dv = cols["potential_energy_j"][-1] - cols["potential_energy_j"][0]
    dk = cols["kinetic_energy_j"][-1] - cols["kinetic_energy_j"][0]
    pin = np.sum(cols["contact_force_n"][:-1] * -np.diff(cols["plate_y_m"]))
    residual = step.sum() - dk - dv - pin - cols["damping_work_j"][1:].sum() - _plays_and_stems(cols)
    assert e["residual_j"] == pytest.approx(residual, rel=1e-9, abs=1e-12)
    assert s["energy_balance_residual"] == pytest.approx(abs(residual) / np.abs(step).sum(), rel=1e-9)
    assert s["energy_balance_residual"] <= sizing.energy_balance_tolerance(e["model"], e["drive_kind"])


def test_balance_over_its_tolerance_is_refused(sized, monkeypatch):
    """With the tolerance just under the board's residual (recomputed from the CSV) the run is refused: exit 2,
    one line naming the residual; just over it, the run passes."""
    case, cols, s = sized
    n, lengths = legs(cols, "act_n"), legs(cols, "length_m")
    step = np.sum(-n[1:] * np.diff(lengths, axis=0), axis=1)
    dv = cols["potential_energy_j"][-1] - cols["potential_energy_j"][0]
    dk = cols["kinetic_energy_j"][-1] - cols["kinetic_energy_j"][0]
    pin = np.sum(cols["contact_force_n"][:-1] * -np.diff(cols["plate_y_m"]))
    relative = abs(step.sum() - dk - dv - pin - cols["damping_work_j"][1:].sum() - _plays_and_stems(cols)
                   ) / np.abs(step).sum()
    key = (model_kind(s["energy_balance"]["model"]), drives.by_kind(s["energy_balance"]["drive_kind"]))
    ratio = sizing.ENERGY_BALANCE[key][1]
    monkeypatch.setitem(sizing.ENERGY_BALANCE, key, (relative * 0.999, ratio))
    res = run("cycle", case, "--no-progress", "--json")
    lines = res.output.strip().splitlines()
    assert res.exit_code == 2 and len(lines) == 1 and "energy balance" in lines[0], res.output
    assert "Traceback" not in res.output
    monkeypatch.setitem(sizing.ENERGY_BALANCE, key, (relative * 1.001, ratio))
    res = run("cycle", case, "--no-progress", "--json")
    assert res.exit_code == 0, res.output

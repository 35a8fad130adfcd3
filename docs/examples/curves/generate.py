"""Make the example monitor files: windows.json, derived from the band of 4000 closed-form pin curves
(pressfit.studies.curve_band.AnalyticPin: a 0.4 mm lead-in to a 120 N plateau, the shoulder seating 1.6 mm past
the first contact, the press stopping at 400 N) over the tolerances below (seed 2026), and six "measured" curves
in the two layouts pressfit reads, each the curve of a pin as the press records it: the tool's depth plus the
machine's deflection at the pin of cases/paper/insertion.toml (the condensed compliance along the press direction
times the force: what `pressfit curves check --compensate` removes), with 0.3 N of force noise (seed 2026).
Run from the repository root: .venv/bin/python docs/examples/curves/generate.py"""

from dataclasses import replace
from pathlib import Path

import numpy as np

from pressfit.description.cases import load_case
from pressfit.output.curve_files import write_windows
from pressfit.studies.curve_band import AnalyticPin, curve_band_study, windows_from_band
from pressfit.studies.curve_check import press_compliance_m_per_n

HERE = Path(__file__).parent
TOLERANCES = {"plateau_force_n": {"distribution": "normal", "mean": 120.0, "std": 6.0},  # hole and pin diameters
              "approach_m": {"distribution": "uniform", "low": 0.45e-3, "high": 0.55e-3},  # board thickness, height
              "seat_depth_m": {"distribution": "uniform", "low": 1.55e-3, "high": 1.65e-3},  # pin length
              "lead_in_m": {"distribution": "uniform", "low": 0.35e-3, "high": 0.45e-3}}  # chamfer
NOMINAL = AnalyticPin(return_stroke=True)

study = curve_band_study(AnalyticPin(), TOLERANCES, 4000, seed=2026, serial=True)
windows = windows_from_band(study.band, press_in_end_m=1.9e-3, name="compliant pin, cases/paper/insertion.toml",
                            source={"generator": "docs/examples/curves/generate.py", "samples": 4000, "seed": 2026,
                                    "tolerances": TOLERANCES})
write_windows(HERE / "windows.json", windows, overwrite=True)

compliance = press_compliance_m_per_n(load_case(Path("cases/paper/insertion.toml")))
rng = np.random.default_rng(2026)


def measured(pin: AnalyticPin, extra=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    x, f = pin()
    if extra is not None:
        f = f + extra(x)
    f = f + rng.normal(0.0, 0.3, f.shape)
    sensed = x + compliance * f
    t = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(sensed)) / 5e-3)])  # 5 mm/s
    return t, sensed, f


def plain(name: str, pin: AnalyticPin, extra=None) -> None:
    t, x, f = measured(pin, extra)
    lines = ["Time [s],Displacement [mm],Force [kN]"]
    lines += [f"{a:.5f},{b * 1e3:.5f},{c / 1e3:.6f}" for a, b, c in zip(t, x, f, strict=True)]
    (HERE / name).write_text("\n".join(lines) + "\n")


def protocol(name: str, part: str, pin: AnalyticPin, extra=None) -> None:
    t, x, f = measured(pin, extra)
    lines = [f"Part number;{part}", "Date;2026-12-06", "Time of day;13:00:00", "Measuring program;3;pin press-in",
             "Total result;-", "", "Zeit;Weg;Kraft", "s;mm;N"]
    lines += [f"{a:.5f};{b * 1e3:.5f};{c:.3f}".replace(".", ",") for a, b, c in zip(t, x, f, strict=True)]
    (HERE / name).write_text("\n".join(lines) + "\n")


plain("ok_part.csv", replace(NOMINAL, plateau_force_n=117.0))
protocol("ok_protocol.csv", "A-0042", replace(NOMINAL, plateau_force_n=124.0, approach_m=0.52e-3))
plain("nok_missing_pin.csv", replace(NOMINAL, plateau_force_n=2.0))  # no pin: no press-in force, only the seat
protocol("nok_bent_pin.csv", "A-0043", NOMINAL,  # the bent pin's tip rides on the board before the hole
         extra=lambda x: np.where((x > 0.15e-3) & (x < 0.5e-3), 35.0 * np.sin(np.pi * (x - 0.15e-3) / 0.35e-3), 0.0))
plain("nok_oversized_hole.csv", replace(NOMINAL, plateau_force_n=85.0))
plain("nok_undersized_hole.csv", replace(NOMINAL, plateau_force_n=160.0))

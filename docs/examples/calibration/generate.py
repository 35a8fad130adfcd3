"""Make the example measurement file: the "built machine" is the shipped one with a softer drive
(4.2e7 N/m instead of 5e7) and thinner cylinder walls (4.6 mm instead of 5 mm); its tool translations under
150 N at the 16 poses and load directions that `pressfit calibrate --plan --load 150 --sigma 2e-6` proposes for these two keys, computed
by the VJM chain (pressfit.mechanics.fast_statics, not the condensed model the fit uses), plus Gaussian noise of
sigma = 2 um per component (seed 2026). Run from the repository root: .venv/bin/python
docs/examples/calibration/generate.py"""

from pathlib import Path

import numpy as np

from pressfit.description.machine import load_machine
from pressfit.mechanics.fast_statics import FastEquilibriumSolver
from pressfit.studies.calibration_model import machine_with, parse_fit_keys
from pressfit.studies.measurement_plan import plan_measurements

KEYS = ["actuator.axial_stiffness_n_per_m", "cylinder.wall_thickness_m"]
BUILT = [4.2e7, 0.0046]
SIGMA_M = 2e-6
LOAD_N = 150.0  # small enough that the largest (lateral) deflection, ~1 mm, stays in the linear range

shipped = load_machine()
plan = plan_measurements(shipped, parse_fit_keys(shipped, KEYS), poses=16, load_n=LOAD_N, sigma_m=SIGMA_M)
built = machine_with(shipped, parse_fit_keys(shipped, KEYS), BUILT)
wrench = np.concatenate([plan.load_n, np.zeros_like(plan.load_n)], 1)
d = FastEquilibriumSolver(built).solve_batch(plan.pose_m, wrench, linear=True).plate_displacement_m
d = d + np.random.default_rng(2026).normal(0.0, SIGMA_M, d.shape)
lines = ["x_m,y_m,z_m,fx_n,fy_n,fz_n,dx_m,dy_m,dz_m,sigma_m"]
lines += [",".join([*(f"{v:.4f}" for v in h), *(f"{v:.1f}" for v in f), *(f"{v:.4e}" for v in x), f"{SIGMA_M:g}"])
          for h, f, x in zip(plan.pose_m, plan.load_n, d, strict=True)]
Path(__file__).with_name("measurements.csv").write_text("\n".join(lines) + "\n")

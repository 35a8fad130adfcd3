"""The D-optimal measurement plan (issue 31): better than chance, and it separates what a centred plan cannot."""

import numpy as np
import pytest

from pressfit.studies.calibration_model import parse_fit_keys
from pressfit.studies.measurement_plan import _candidates, plan_measurements

KEYS = ["actuator.axial_stiffness_n_per_m", "stem.diameter_m"]


@pytest.fixture(scope="module")
def plan_and_candidates(machine):
    keys = parse_fit_keys(machine, KEYS)
    return plan_measurements(machine, keys, poses=6), _candidates(machine, keys, 700.0, 1e-6)


def test_the_plan_beats_random_plans_of_the_same_size(plan_and_candidates):
    """The greedy D-optimal plan's log det information is above that of each of 200 random 6-measurement
    subsets of the same candidates (computed here from the candidates' sensitivities, not by the planner)."""
    plan, (pose, load, g) = plan_and_candidates
    rng = np.random.default_rng(0)
    per = np.einsum("cik,cil->ckl", g, g)
    random = [np.linalg.slogdet(per[rng.choice(len(per), 6, replace=False)].sum(0))[1] for _ in range(200)]
    assert plan.log_det_information > max(random)


def test_the_planned_errors_follow_from_the_planned_rows(plan_and_candidates):
    """sqrt(diag((sum G^T G)^-1)) recomputed from the chosen candidates (the ridge is 1e-9 of one candidate)."""
    plan, (pose, load, g) = plan_and_candidates
    rows = [int(np.flatnonzero(np.all(pose == p, 1) & np.all(load == f, 1))[0])
            for p, f in zip(plan.pose_m, plan.load_n, strict=True)]
    info = np.einsum("cik,cil->kl", g[rows], g[rows])
    assert plan.standard_error_theta == pytest.approx(np.sqrt(np.diag(np.linalg.inv(info))), rel=1e-6)
    assert len(set(rows)) == 6

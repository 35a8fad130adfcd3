"""Design study (pressfit study design): a one-parameter problem with a closed-form optimum, the machine files
it writes, identical results with 1 and 2 Dask workers, and the [design] table's validation."""

import math
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from pressfit import kinematics
from pressfit.description.cases import DesignConstraints, load_case
from pressfit.description.machine import load_machine
from pressfit.errors import ModelFileError
from pressfit.shipped import cases_dir
from pressfit.studies import design
from pressfit.workflows import design_study

Y_M = 0.65
D_STAR_M = 0.02523  # the stem diameter whose vertical stiffness is the constraint's limit (not a grid value)


def one_parameter_case(tmp_path: Path, k_min: float = 1.0, extra: str = "") -> Path:
    """Stem diameter d in [15, 35] mm on a 41-point grid (0.5 mm steps), minimise the moving mass (grows with
    d) subject to a minimum vertical stiffness (grows with d); a 2 um square at one height, so the
    workspace is the centre pose where the closed form below holds."""
    p = tmp_path / "one.toml"
    p.write_text(f"""name = "one-parameter"
[model_overrides.workspace]
x_half_width_m = 1.0e-6
z_half_width_m = 1.0e-6
[poses]
points_m = [[0.0, {Y_M}, 0.0]]
[loads]
force_n = [0.0, 700.0, 0.0]
[design]
search = "grid"
grid_points = 41
objectives = ["moving_mass_kg"]
heights_m = [{Y_M}, {Y_M}]
height_levels = 1
grid_xz = 2
[design.parameters]
stem_diameter_m = [0.015, 0.035]
[design.constraints]
min_vertical_stiffness_n_per_m = {float(k_min)!r}
{extra}""")
    return p


def vertical_stiffness(machine, stem_diameter_m: float) -> float:
    """Closed form at the centre pose: the four legs are symmetric, so K_t = sum k_a e e^T is diagonal and the
    moment arm h - P* is vertical; a vertical force moves the plate by F / (4 k_a e_y^2), with
    1 / k_a = 1 / k_act + L_c / (E A_c) + (l - L_c) / (E A_s) (actuator, cylinder, stem in series)."""
    u = kinematics.leg_vectors(machine, np.array([0.0, Y_M, 0.0]))[0]
    length = float(np.linalg.norm(u))
    e, lc = machine.material.youngs_modulus_pa, machine.cylinder.length_m
    c = (1 / machine.actuator.axial_stiffness_n_per_m + lc / (e * machine.cylinder_section.area_m2)
         + (length - lc) / (e * math.pi / 4 * stem_diameter_m**2))
    return 4 * (u[1] / length) ** 2 / c


@pytest.mark.slow
def test_the_front_ends_at_the_closed_form_optimum(tmp_path):
    """The least moving mass under a binding stiffness limit is the smallest feasible stem: the first grid value
    at or above d*, where the closed-form vertical stiffness equals the limit (exact to the grid step)."""
    machine = load_case(one_parameter_case(tmp_path)).machine()
    k_min = vertical_stiffness(machine, D_STAR_M)
    plan = design.plan_from_case(load_case(one_parameter_case(tmp_path, k_min)))
    cols = design.evaluate_designs(plan, 0, design._grid(plan))
    front = np.flatnonzero(design.pareto_mask(cols["moving_mass_kg"][:, None], cols["feasible"]))
    assert len(front) == 1
    d_best = cols["stem_diameter_m"][front[0]]
    assert d_best - 0.0005 < D_STAR_M <= d_best, (d_best, D_STAR_M)
    assert np.all(np.diff(cols["moving_mass_kg"]) > 0)  # the objective is monotone: the constraint binds
    # the condensed model's vertical stiffness against the closed form, every grid value: off the centre by
    # x, the moment arm h - P* tilts and C_yy gains ~(x r / (p - r))^2 / k_rot, ~1e-8 relative at x = 1 um
    # (1.6e-4 measured at x = 0.1 mm, scaling as x^2): tolerance 1e-7
    k = np.array([vertical_stiffness(machine, d) for d in cols["stem_diameter_m"]])
    np.testing.assert_allclose(1 / cols["max_vertical_compliance_m_per_n"], k, rtol=1e-7)


def test_pareto_mask_keeps_the_non_dominated_feasible_rows():
    f = np.array([[1.0, 5.0], [2.0, 2.0], [3.0, 3.0], [0.5, 9.0], [0.1, 0.1]])
    feasible = np.array([True, True, True, True, False])
    np.testing.assert_array_equal(design.pareto_mask(f, feasible), [True, True, False, True, False])


@pytest.fixture(scope="module")
def small_study(tmp_path_factory, cluster):
    """The small study on a local cluster of one worker (``workers=1``, the command's default path) and on the shared
    two-worker cluster by its address."""
    case = load_case(cases_dir() / "studies" / "design_sections.toml")
    case = case.model_copy(update={"design": case.design.model_copy(update={  # only the height range constrains
        "population": 4, "grid_xz": 5, "constraints": DesignConstraints()})})
    out = tmp_path_factory.mktemp("design")
    one = design_study.run_design_study(case, out / "one", trials=8, workers=1, progress=False)
    two = design_study.run_design_study(case, out / "two", trials=8, scheduler=cluster.scheduler_address,
                                        progress=False)
    return out, one, two


def test_one_and_two_workers_give_the_same_designs(small_study):
    """NSGA-II is seeded and generations are told in trial order: the trials are bit for bit the same."""
    out, _, _ = small_study
    a, b = pq.read_table(out / "one" / "trials.parquet"), pq.read_table(out / "two" / "trials.parquet")
    assert a.num_rows == 8 and a.column_names == b.column_names
    for k in a.column_names:  # bit for bit (NaN of a failed design equal to NaN)
        np.testing.assert_array_equal(a.column(k).to_numpy(zero_copy_only=False),
                                      b.column(k).to_numpy(zero_copy_only=False), err_msg=k)
    assert len(set(a.column("base_half_side_m").to_pylist())) == 8  # the sampler really varied the designs


def test_written_designs_load_as_machines(small_study):
    out, one, _ = small_study
    files = sorted((out / "one" / "designs").glob("*.toml"))
    assert files, one.result.columns["status"]
    c = one.result.columns
    for f in files:
        m = load_machine(f)
        i = int(f.stem.split("-")[1])
        assert c["pareto"][i]
        assert m.geometry.base_half_side_m == c["base_half_side_m"][i]
        assert m.stem.diameter_m == c["stem_diameter_m"][i]
        assert m.collision.stem_radius_m == c["stem_diameter_m"][i] / 2
    assert (out / "one" / "pareto.png").stat().st_size > 0


def test_the_pareto_figure_shows_the_trials_and_the_front(small_study):
    """pareto.png's figure: the feasible trials at their (objective 1, objective 2) and the front's line through
    the Pareto trials, as the trial table holds them; the axes named by the objectives and spanning the front."""
    from pressfit.output.design_files import pareto_figure
    from pressfit.output.plots import plt

    _, one, _ = small_study
    r = one.result
    c, (x, y) = r.columns, r.plan.design.objectives[:2]
    fig = pareto_figure(r)
    try:
        ax = fig.axes[0]
        assert (ax.get_xlabel(), ax.get_ylabel()) == (x, y)
        np.testing.assert_array_equal(ax.collections[1].get_offsets(), np.column_stack([c[x], c[y]])[c["feasible"]])
        np.testing.assert_array_equal(ax.lines[0].get_xydata(), np.column_stack([c[x][r.pareto], c[y][r.pareto]]))
        lo, hi = ax.get_xlim()
        assert lo <= c[x][r.pareto].min() and hi >= c[x][r.pareto].max()
    finally:
        plt.close(fig)


def test_a_reversed_range_is_a_named_error(tmp_path):
    p = one_parameter_case(tmp_path).read_text().replace("stem_diameter_m = [0.015, 0.035]",
                                                        "stem_diameter_m = [0.035, 0.015]")
    (tmp_path / "bad.toml").write_text(p)
    with pytest.raises(ModelFileError, match="stem_diameter_m must be"):
        load_case(tmp_path / "bad.toml")


def test_a_grid_beyond_the_cap_is_refused_before_it_is_built(tmp_path):
    """grid_points = 1000 over 5 parameters would be 1e15 designs (old code: built them): refused by the case
    schema naming the key and the cap; the cap itself (MAX_GRID_DESIGNS = 100000) is accepted, one point
    above it is not (316^2 = 99856 <= 1e5 < 317^2 = 100489)."""
    from click.testing import CliRunner

    from pressfit.cli import main
    from pressfit.description.cases import MAX_GRID_DESIGNS

    assert MAX_GRID_DESIGNS == 100_000
    two = "stem_diameter_m = [0.015, 0.035]\nbase_half_side_m = [0.4, 0.5]"
    five = (two + "\nplate_half_side_m = [0.1, 0.2]\ncylinder_outer_diameter_m = [0.04, 0.06]\n"
            "cylinder_wall_thickness_m = [0.003, 0.005]")
    for points, params, ok in [(316, two, True), (317, two, False), (1000, five, False)]:
        p = one_parameter_case(tmp_path).read_text().replace("grid_points = 41", f"grid_points = {points}")
        (tmp_path / "g.toml").write_text(p.replace("stem_diameter_m = [0.015, 0.035]", params))
        if ok:
            assert load_case(tmp_path / "g.toml").design.grid_points == points
            continue
        with pytest.raises(ModelFileError, match=f"key 'design': .*grid_points = {points} over .* above the cap of "
                                                 "100000 designs") as err:
            load_case(tmp_path / "g.toml")
        assert "\n" not in str(err.value)
    result = CliRunner().invoke(main, ["study", "design", str(tmp_path / "g.toml"), "--out", str(tmp_path / "o")])
    assert result.exit_code == 2 and result.output.count("\n") == 1 and "grid_points = 1000" in result.output
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_overwrite_never_replaces_the_case_file_with_a_design(tmp_path, monkeypatch, cluster):
    """A case file that sits where the study writes a design (``designs/design-NNNNNN.toml``) is an input: a rerun
    with --overwrite is refused before the study is computed (its names come from its results), naming both, and
    the case file is unchanged; a case beside the directory runs."""
    from pressfit.errors import OutputConflictError
    from pressfit.studies import design

    out, on = tmp_path / "out", {"scheduler": cluster.scheduler_address}  # the shared cluster (tests/conftest.py)
    first = design_study.run_design_study(load_case(one_parameter_case(tmp_path)), out, **on, progress=False)
    target = next(p for p in first.written if p.parent.name == "designs")
    target.write_text(one_parameter_case(tmp_path).read_text())
    before = target.read_text()

    def computed(*args, **kwargs):
        raise AssertionError("the study was computed before the refusal")

    monkeypatch.setattr(design, "run_design", computed)
    with pytest.raises(OutputConflictError, match=r"holds the input file .*design-\d{6}\.toml") as refused:
        design_study.run_design_study(load_case(target), out, **on, overwrite=True, progress=False)
    assert refused.value.option == "--out" and refused.value.other == str(target)
    assert target.read_text() == before
    with pytest.raises(AssertionError, match="computed before"):  # outside the directory: it goes on to compute
        design_study.run_design_study(load_case(one_parameter_case(tmp_path)), out, **on, overwrite=True,
                                      progress=False)

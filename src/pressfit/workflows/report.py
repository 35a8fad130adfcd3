"""``pressfit report``: one Markdown report of everything pressfit computes for a machine (each section computes
its results and hands them to output/'s writers: maps, simulation, cycle, compare, html_report).

Sections: the paper's Tables 5-6 beside pressfit, the kinematic maps and workspace claims, the
workspace load envelope (design loads), stiffness maps, the clearance-vs-preload study, the leg
interference summary, the paper's insertion and the shipped board's work cycle (with a throughput study's front
when given), the machines compared, and the joint and its press curve. Every number comes from the same library
functions the CLI and tests call.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
from tqdm import tqdm

from pressfit.description.cases import Case, Pin, load_case
from pressfit.description.machine import Machine
from pressfit.dynamics.insertion import simulate_insertion
from pressfit.errors import PressfitError
from pressfit.geometry import interference
from pressfit.kinematics import workspace
from pressfit.mechanics import condensed
from pressfit.mechanics.statics import Equilibrium, solve_equilibrium
from pressfit.output import maps, plots
from pressfit.output.calibration_files import read_calibration, report_section
from pressfit.output.curve_files import BOARD_PIN_COLUMNS, JOINT_CURVE_KEYS, write_joint_files
from pressfit.output.files import write_csv, write_json, write_text
from pressfit.output.html_report import ReportContent, write_html_report
from pressfit.output.scene3d import SceneCase
from pressfit.output.simulation import write_simulation
from pressfit.shipped import cases_dir
from pressfit.studies import cad_fit, joint_curves, preload_study, workspace_envelope
from pressfit.studies import paper_tables as tables
from pressfit.studies.cycle_study import FACTORS, FRONT_FIGURES
from pressfit.workflows.kinematic_maps import write_kinematic_maps


def _md_table(header: list[str], rows: list[list[object]]) -> str:
    fmt = lambda v: f"{v:.4g}" if isinstance(v, float) else str(v)
    return "\n".join(["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
                     + ["| " + " | ".join(fmt(v) for v in r) + " |" for r in rows])


@dataclasses.dataclass(frozen=True, kw_only=True)
class Resolution:
    """The grids, sample counts and time steps of one kind of report (``QUICK``, ``DEFAULT``, ``FULL``)."""

    name: str
    figures: bool  # the static PNG maps (report.html has every map, interactive)
    kinematic_heights_m: tuple[float, ...]
    envelope_heights: int  # y_h levels over 0.5 ... 0.75 m
    envelope_grid: int  # per side of the square
    stiffness_heights_m: tuple[float, ...]
    stiffness_grid: int
    preloads_n: tuple[float, ...]
    preload_poses: int  # pose A, then off-centre
    preload_load_steps: int
    interference_points: int
    interference_heights: int
    time_step_s: float | None  # the insertion's and the board cycle's step; None: the cases' own (1 ms)
    quick_board: bool  # the board's first QUICK_BOARD_PINS pins only, 0.1 s dwell
    compare_box: tuple[int, int] | None  # (heights, grid); None: pressfit compare's own (3 x 5 x 5)
    band_samples: int
    cad_fit_without_couple_stress: bool


FULL_PRELOADS_N = (0.0, 100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 800.0, 1000.0, 1200.0)
FULL = Resolution(name="full", figures=True, kinematic_heights_m=tuple(workspace.DEFAULT_HEIGHTS_M),
                  envelope_heights=11, envelope_grid=41, stiffness_heights_m=(0.6, 0.72), stiffness_grid=51,
                  preloads_n=FULL_PRELOADS_N, preload_poses=2, preload_load_steps=50, interference_points=41,
                  interference_heights=9, time_step_s=None, quick_board=False, compare_box=None,
                  band_samples=joint_curves.REPORT_BAND_SAMPLES, cad_fit_without_couple_stress=True)
# The README's main command: the full report's grids, with the insertion and the board cycle at 2 ms (the step
# --quick uses): cycle time, pins passed and settling unchanged, forces and drive figures within 0.4% of 1 ms, the
# overshoot within 2%, the sub-micron lateral error at first contact within 60% (docs/benchmarks.md). The compare box
# stays 3 x 5 x 5: on 3 x 3 x 3 the share of the box where a claim holds moves (84% -> 56%: corners over-weighted).
DEFAULT = dataclasses.replace(FULL, name="default", time_step_s=2e-3)
QUICK = Resolution(name="quick", figures=False, kinematic_heights_m=(0.6,), envelope_heights=3, envelope_grid=11,
                   stiffness_heights_m=(0.72,), stiffness_grid=21, preloads_n=(0.0, 200.0, 400.0, 600.0),
                   preload_poses=1, preload_load_steps=10, interference_points=11, interference_heights=3,
                   time_step_s=2e-3, quick_board=True, compare_box=(2, 3), band_samples=100,
                   cad_fit_without_couple_stress=False)


def resolution_note(res: Resolution) -> str:
    """The report's first paragraph: the grids, sample counts and steps it used, and how to get the full ones."""
    step = "the cases' own (1 ms)" if res.time_step_s is None else f"{res.time_step_s * 1e3:g} ms"
    heights, grid = res.compare_box or (3, 5)
    box = f"{heights} x {grid} x {grid}"
    how = {"full": "This is the full-resolution report (`--full`).",
           "default": "`pressfit report --full` runs the insertion and the board cycle at the cases' own 1 ms step "
                      "(about 20 s more CPU); `--quick` is a coarser preview.",
           "quick": "A preview (`--quick`): coarse grids, no static PNG maps; `pressfit report` for the design grids, "
                    "`--full` for the full resolution."}[res.name]
    return (f"Resolution ({res.name}): kinematic maps at y_h = {', '.join(f'{y:g}' for y in res.kinematic_heights_m)}"
            f" m; envelope "
            f"{res.envelope_heights} heights x {res.envelope_grid} x {res.envelope_grid} poses; stiffness maps "
            f"{res.stiffness_grid} x {res.stiffness_grid} at {len(res.stiffness_heights_m)} heights; preload study "
            f"{len(res.preloads_n)} preloads x {res.preload_load_steps} load steps at {res.preload_poses} poses; "
            f"interference {res.interference_heights} heights x {res.interference_points} x "
            f"{res.interference_points}; insertion and board cycle time step {step}; machines compared on a {box} "
            f"box; joint band {res.band_samples} samples. {how}")


def write_report(machine: Machine, out_dir: Path | str, overwrite: bool = False, quick: bool = False,
                 full: bool = False, progress: bool = True, cycle_study: Path | str | None = None,
                 calibration: Path | str | None = None) -> Path:
    """Compute every section and write ``report.md`` with its figures, CSV and JSON into ``out_dir``, and
    the interactive ``report.html`` (:mod:`pressfit.output.html_report`) beside it; returns report.md's path.

    ``quick`` (a preview, and the tests: :data:`QUICK`) uses coarser grids and writes no static PNG maps
    (report.html shows the same maps interactively); the default (:data:`DEFAULT`) is the design grids with the
    insertion and the board cycle at a 2 ms step; ``full`` (:data:`FULL`) runs them at the cases' own step.
    ``cycle_study``: the directory of a ``pressfit study cycle`` run whose front the board's section shows.
    ``calibration``: the ``--out`` directory of a ``pressfit calibrate`` run, whose results get their own section.
    """
    if quick and full:
        raise PressfitError("report: --quick and --full exclude each other")
    res = QUICK if quick else FULL if full else DEFAULT
    out = Path(out_dir)
    study = None if cycle_study is None else read_cycle_study(cycle_study)  # checked before computing
    fitted = None if calibration is None else read_calibration(calibration)
    steps = tqdm(total=11, desc="report", disable=not progress, unit="section")
    md = [f"# pressfit report: {machine.name}", "",
          f"Machine file: `{machine.source}`. SI units throughout. Interactive version "
          "(3D view of the loaded machine, sortable tables, zoomable plots): [report.html](report.html).", "",
          resolution_note(res), ""]
    sections = (_tables_section, _kinematics_section, _envelope_section, _stiffness_section, _preload_section,
                _interference_section, _insertion_section, _cycle_section, _compare_section, _joint_section)
    parts: dict[str, object] = {"cycle_study": study}
    for section in sections:
        md += section(machine, out, overwrite, res, parts)
        steps.update()
    if fitted is not None:
        md += report_section(fitted, calibration)
    write_json(out / "summary.json", {"workspace": parts["summary"], "interference": parts["interference"]
                                      .kind_minima()}, overwrite)
    path = write_text(out / "report.md", "\n".join(md) + "\n", overwrite)
    scene = [_worst_case(machine, parts["envelope"])] + [
        _scene_case(f"paper case {s.case.name.removeprefix('paper-')}", s.nonlinear) for s in parts["solutions"]]
    sweep = parts["interference"]
    write_html_report(out, ReportContent(
        machine=machine, scene=scene, tables=[e.as_dict() for e in parts["entries"]], plane_maps=parts["plane_maps"],
        required_square_m=workspace.square_corners(machine),
        envelope=parts["envelope"], envelope_table=parts["envelope_table"], stiffness=parts["stiffness"],
        preload=parts["studies"], interference=sweep,
        interference_table=[{"kind": k, **v} for k, v in sweep.kind_minima().items()], insertion=parts["insertion"],
        cycle=parts["cycle"], cycle_front=parts["cycle_front"], comparison=parts["comparison"],
        joint=parts["joint"]), overwrite)
    steps.update()
    steps.close()
    return path


Parts = dict[str, object]  # what one section computed and a later one (or the HTML page) shows


def _tables_section(machine: Machine, out: Path, overwrite: bool, res: Resolution, parts: Parts) -> list[str]:
    parts["solutions"] = solutions = tables.solve_paper_cases()
    parts["entries"] = entries = tables.paper_tables(solutions=solutions)
    write_text(out / "tables.md", tables.to_markdown(entries), overwrite)
    write_csv(out / "tables.csv", *tables.to_rows(entries), overwrite=overwrite)
    write_json(out / "tables.json", [e.as_dict() for e in entries], overwrite)
    md = ["## 1. The paper's Tables 5 and 6", "",
          "Cases A, B, C of `cases/paper/` (700 N press reaction, +y, at the plate centre), actuator section. "
          "The map from the paper's CAD legs, signs and axes to ours is stated in `pressfit/studies/paper_tables.py`;"
          " why B and C differ from the paper is explained in README.md (\"Tables 5 and 6\").", "",
          tables.to_markdown(entries)]
    return md + cad_fit_section(out, overwrite, res.cad_fit_without_couple_stress)


def _kinematics_section(machine: Machine, out: Path, overwrite: bool, res: Resolution, parts: Parts) -> list[str]:
    heights = list(res.kinematic_heights_m)
    summ, _, parts["plane_maps"] = write_kinematic_maps(machine, out / "kinematics", heights, overwrite=overwrite,
                                                            figures=res.figures)
    parts["summary"] = summ
    rng = summ["height_range"][0]
    return ["## 2. Kinematics and workspace (paper section 4.1)", "",
            f"The required {2 * machine.workspace.x_half_width_m * 1000:g} x "
            f"{2 * machine.workspace.z_half_width_m * 1000:g} mm square is reachable for y_h in "
            f"[{rng['y_min_m']:.5f}, {rng['y_max_m']:.5f}] m.", "",
            _md_table(["y_h [m]", "square rotation [deg]", "n min", "n max", "n variation", "F_y max"],
                      [[s["y_m"], s["angle_deg"], s["dexterity_min"], s["dexterity_max"],
                        s["dexterity_variation"], s["force_index_max"][1]] for s in summ["squares"]]), ""
            ] + [f"![maps y={y:.3f}](kinematics/maps_y{y:.3f}.png)" for y in heights if res.figures] + [""]


def _envelope_section(machine: Machine, out: Path, overwrite: bool, res: Resolution, parts: Parts) -> list[str]:
    ys = np.linspace(0.5, 0.75, res.envelope_heights)
    parts["envelope"] = env = workspace_envelope.load_envelope(
        machine, ys, n_xz=res.envelope_grid, loads_n=workspace_envelope.press_loads(700.0, np.radians(5.0)),
        progress=False)
    maps.write_load_envelope(env, out / "envelope", overwrite, figures=res.figures)
    header, rows = workspace_envelope.envelope_rows(env)
    parts["envelope_table"] = [dict(zip(header, r)) for r in rows]
    return ["## 3. Workspace load envelope (design loads)", "",
            f"700 N press reaction within a 5 degree cone, over the required square at y_h = {ys[0]:g} ... "
            f"{ys[-1]:g} m; exact condensed linear model (docs/conventions.md). Use `pressfit check` with a case "
            "file to refine the worst poses with the nonlinear solver.", "", _md_table(header, rows), ""
            ] + [f"![{p.name}](envelope/{p.name})" for p in sorted((out / "envelope").glob("*.png"))] + [""]


def _stiffness_section(machine: Machine, out: Path, overwrite: bool, res: Resolution, parts: Parts) -> list[str]:
    md = ["## 4. Stiffness", ""]
    parts["stiffness"] = stiffness = [condensed.stiffness_maps(machine, y, n=res.stiffness_grid)
                                      for y in res.stiffness_heights_m]
    for smaps in stiffness:
        paths = maps.write_stiffness_maps(smaps, out / "stiffness", overwrite, figures=res.figures)
        md += [f"![{p.name}](stiffness/{p.name})" for p in paths if p.suffix == ".png"]
    return md + [""]


def _interference_section(machine: Machine, out: Path, overwrite: bool, res: Resolution, parts: Parts) -> list[str]:
    im = interference.build_interference(machine)
    parts["interference"] = sweep = interference.workspace_sweep(im, points=res.interference_points,
                                                                 heights=res.interference_heights)
    maps.write_interference_sweep(sweep, out / "interference", overwrite, figures=res.figures)
    return ["## 6. Leg interference (Coal)", "",
            f"Minimum signed distance per pair kind over the required workspace (capsule legs; margin "
            f"{sweep.margin_m * 1000:g} mm: {'PASS' if sweep.passed else 'FAIL'}).", "",
            _md_table(["pair kind", "min distance [m]", "pair", "pose [m]"],
                      [[k, v["distance_m"], v["pair"], np.round(v["pose_m"], 4).tolist()]
                       for k, v in sweep.kind_minima().items()]), ""
            ] + [f"![{p.name}](interference/{p.name})" for p in sorted((out / "interference").glob("*.png"))] + [""]


def _insertion_section(machine: Machine, out: Path, overwrite: bool, res: Resolution, parts: Parts) -> list[str]:
    """The paper's insertion scenario (``cases/paper/insertion.toml``) with and without the force limiter."""
    case = load_case(cases_dir() / "paper" / "insertion.toml")
    if res.time_step_s is not None:  # the schema's coarsest step, 2 ms (peak, steady force within 0.1% of 1 ms)
        simulation = case.simulation.model_copy(update={"time_step_s": res.time_step_s})
        case = case.model_copy(update={"simulation": simulation})
    runs = simulate_insertion(case, limiter=True), simulate_insertion(case, limiter=False)
    parts["insertion"] = runs
    write_simulation(runs[0], out / "insertion", overwrite, comparison=runs[1])
    keys = ("peak_contact_force_n", "overshoot_n", "steady_insertion_force_n", "steady_insertion_depth_m",
            "positioning_error_m", "settling_time_s")
    return ["## 7. Pin insertion (paper section 4.2, Figures 12-14)", "",
            f"`{case.path}` at a {case.simulation.time_step_s * 1e3:g} ms step: force-limited position control, 40 Hz "
            "force-controlled actuators, the machine's compliance in series with an elastic pin-board contact; with "
            "and without the force limiter "
            "(`pressfit simulate`).", "",
            _md_table(["quantity", "with the limiter", "without"],
                      [[k, *("did not settle" if r.summary[k] is None else r.summary[k] for r in runs)]
                       for k in keys]), "",
            "![insertion](insertion/simulation.png)", ""]


QUICK_BOARD_PINS = 2  # --quick: the shipped board's first pins only, 0.1 s dwell, 2 ms step (a preview)
CYCLE_PIN_KEYS = ("index", "x_m", "z_m", "first_contact_time_s", "peak_contact_force_n", "steady_insertion_force_n",
                  "overshoot_n", "tool_lateral_error_at_first_contact_m", "settling_time_s", "passed")
CYCLE_DRIVE_KEYS = ("leg", "peak_force_n", "rms_force_n", "rms_force_without_preload_n", "peak_speed_m_per_s",
                    "peak_power_w", "positive_energy_j", "regenerative_energy_j")


def quick_board(case: Case) -> Case:
    """The shipped board shortened for ``--quick``: its first ``QUICK_BOARD_PINS`` pins, 0.1 s dwell, 2 ms step."""
    cycle = case.cycle
    pins = [Pin(x_m=p.x_m, z_m=p.z_m) for p in cycle.resolved_pins()[:QUICK_BOARD_PINS]]
    short = cycle.model_copy(update={"pins": pins, "grid": None, "dwell_s": 0.1, "time_step_s": 2e-3})
    return case.model_copy(update={"cycle": short})


def read_cycle_study(directory: Path | str) -> dict:
    """The summary.json of a ``pressfit study cycle`` run in ``directory``, its front rows checked for every key the
    report shows (PressfitError naming the file and the first missing key)."""
    summary = Path(directory) / "summary.json"
    try:
        front = json.loads(summary.read_text())
    except (OSError, ValueError) as exc:
        raise PressfitError(f"{summary}: the summary.json of a `pressfit study cycle` run: {exc}") from None
    rows = front.get("front") if isinstance(front, dict) else None
    missing = ("front" if not isinstance(rows, list) else
               next((f"front[{i}].{k}" for i, r in enumerate(rows) for k in ("sample", *FACTORS, *FRONT_FIGURES)
                     if not isinstance(r, dict) or k not in r), None))
    if missing is not None:
        raise PressfitError(f"{summary}: the summary.json of a `pressfit study cycle` run has no {missing} (a study "
                            "of another pressfit version? run the study again)")
    return front


def _cycle_section(machine: Machine, out: Path, overwrite: bool, res: Resolution, parts: Parts) -> list[str]:
    """The shipped board (``cases/paper/board.toml``, its own machine, on its [cycle] model; ``quick``: shortened,
    :func:`quick_board`; at ``res.time_step_s``) with the drive sizing, and the front of a throughput study when one
    is given."""
    from pressfit.dynamics.cycle import simulate_cycle
    from pressfit.output.cycle import write_cycle

    case = load_case(cases_dir() / "paper" / "board.toml")
    if res.quick_board:
        case = quick_board(case)
    elif res.time_step_s is not None:
        case = case.model_copy(update={"cycle": case.cycle.model_copy(update={"time_step_s": res.time_step_s})})
    result = simulate_cycle(case)
    parts["cycle"] = result
    write_cycle(result, out / "cycle", overwrite)
    front = parts["cycle_front"] = parts["cycle_study"]
    if front is not None:
        write_json(out / "cycle" / "study_summary.json", front, overwrite)
    s = result.summary
    md = ["## 8. The shipped board's work cycle (issue 20)", "",
          f"`{case.path}`" + (f", shortened for --quick to its first {QUICK_BOARD_PINS} pins, 0.1 s dwell"
                              if res.quick_board else "") + f", at a {case.cycle.time_step_s * 1e3:g} ms step "
          f"(`pressfit cycle`, model {s['model']}): cycle time "
          f"{s['cycle_time_s']:.4g} s, {s['pins_per_minute']:.4g} pins per minute, {s['pins_passed']} of "
          f"{s['pin_count']} pins pass; energy balance residual {100 * s['energy_balance_residual']:.2g}% of the "
          "drives' gross work.", "",
          _md_table(list(CYCLE_PIN_KEYS), [[p[k] for k in CYCLE_PIN_KEYS] for p in s["pins"]]), "",
          _md_table(list(CYCLE_DRIVE_KEYS), [[d.get(k) for k in CYCLE_DRIVE_KEYS] for d in s["drives"]]), "",
          "![board force](cycle/cycle_force.png)", "", "![drives](cycle/cycle_drives.png)", ""]
    if front is not None:
        md += [f"Throughput study ({front['samples']} samples): Pareto front of cycle time, worst alignment error and "
               "worst overshoot:", "",
               _md_table([*FACTORS, *FRONT_FIGURES], [[r[k] for k in (*FACTORS, *FRONT_FIGURES)]
                                                        for r in front["front"]]), ""]
    return md


COMPARED = ("tsai_3upu.toml", "gantry_cartesian.toml", "pressfit_4upu_rotated45.toml")  # beside the report's machine


def _compare_section(machine: Machine, out: Path, overwrite: bool, res: Resolution, parts: Parts) -> list[str]:
    """The report's machine beside the shipped baselines (``COMPARED``; :mod:`pressfit.studies.compare`), and the
    paper's claims decided, on ``res.compare_box`` (--quick: a 2 x 3 x 3 box instead of 3 x 5 x 5)."""
    from pressfit.description.gantry import load_gantry
    from pressfit.description.machine import load_machine
    from pressfit.output.compare import CSV_COLUMNS, write_compare
    from pressfit.shipped import models_dir
    from pressfit.studies.compare import COMPARE_GRID, COMPARE_HEIGHTS, compare

    others = [load_gantry(models_dir() / f) if f.startswith("gantry") else load_machine(models_dir() / f)
              for f in COMPARED]
    others = [m for m in others if m.name != machine.name]  # a report on a baseline shows it once
    heights, grid = res.compare_box or (COMPARE_HEIGHTS, COMPARE_GRID)
    result = compare([machine, *others], progress=False, heights=heights, grid=grid)
    parts["comparison"] = result
    write_compare(result, out / "compare", overwrite)
    figures = [m.to_dict() for m in result.machines]
    md = ["## 9. The machines compared (issue 21: `pressfit compare`)", "",
          f"The report's machine beside Tsai's 3-UPU, the Cartesian gantry of Figure 2 and the 4-UPU turned 45 "
          f"degrees, each over its required box ({heights} x {grid} x {grid} = {result.machines[0].poses} poses"
          f"{'; `pressfit compare` and --full: 3 x 5 x 5' if res.compare_box else ''}) under the 700 N press load and "
          "its 5 degree cone.", "",
          _md_table(["figure", *[f["name"] for f in figures]],
                    [[k, *[f[k] for f in figures]] for k in CSV_COLUMNS[4:]]), "",
          *[f"- **{c.verdict}** ({c.baseline}): {c.claim}. {c.evidence}." for c in result.claims], "",
          "![compare](compare/compare.png)", ""]
    return md


def _joint_section(machine: Machine, out: Path, overwrite: bool, res: Resolution, parts: Parts) -> list[str]:
    """The joint and its press curve (issue 30): the shipped compliant-pin case's predicted curve, its band from a
    small serial Monte Carlo and the windows derived from it, and the shipped board's per-pin curves
    (:func:`pressfit.studies.joint_curves.joint_curves`; each case on its own machine)."""
    pin_case = load_case(cases_dir() / "paper" / "insertion_compliant_pin.toml")
    board = load_case(cases_dir() / "paper" / "board.toml")
    parts["joint"] = joint = joint_curves.joint_curves(pin_case, board, samples=res.band_samples)
    write_joint_files(joint, out / "joint", overwrite)
    c, pins = joint.curve, [p.summary() for p in joint.board]
    spread = [p["sensed_minus_true_depth_at_peak_m"] for p in pins]
    md = ["## 10. The joint and its press curve (issue 30)", "",
          f"`{pin_case.path}` (`pressfit curve`): the press curve predicted quasi-statically, the pins' law in series "
          "with the machine's 6x6 compliance at the pin pose; the monitor records the SENSED depth (the drives' "
          "encoders), which includes the press's own deflection. Its tolerance band is a small Monte Carlo of "
          f"{joint.study.band.samples} samples over `[curve.tolerances]`, serial (`pressfit study curve` runs the "
          "design band: 1000 samples and more, on Dask); the windows are derived from the band by the rules of "
          "docs/monitor.md. Their files: `joint/`.", "",
          _md_table(["quantity (SI)", "value"], [[k, "-" if c.summary()[k] is None else c.summary()[k]]
                                                 for k in JOINT_CURVE_KEYS]), "",
          _md_table(["window element", "kind"], [[e.name, type(e).__name__] for e in joint.windows.elements]), "",
          f"`{board.path}`: every pin of the board pressed quasi-statically with the board's `[cycle.contact]` "
          "law at its own pose, up to its force limit: the true curves coincide, the sensed ones are skewed by the "
          f"compliance along the press at each pose (sensed minus true depth at the peak {min(spread) * 1e6:.3g} to "
          f"{max(spread) * 1e6:.3g} um over the board).", "",
          _md_table(list(BOARD_PIN_COLUMNS), [[p[k] for k in BOARD_PIN_COLUMNS] for p in pins]), "",
          "![joint](joint/joint.png)", ""]
    return md


def cad_fit_section(out: Path, overwrite: bool, without_couple_stress: bool) -> list[str]:
    """The CAD-model identification (a hypothesis beside Table 3): Markdown lines; writes cad_fit.md/.json/.csv
    and a residual chart; ``without_couple_stress`` adds the comparison fit without couple self-stresses."""
    fit = cad_fit.fit_cad_model(compare_without_couple_stress=without_couple_stress)
    text = cad_fit.to_markdown(fit)
    write_text(out / "cad_fit.md", text, overwrite)
    write_json(out / "cad_fit.json", cad_fit.to_dict(fit), overwrite)
    write_csv(out / "cad_fit.csv", ["case", "quantity", "cad_leg", "printed", "sigma", "table3", "fitted"],
              [[e.case, e.quantity, e.cad_leg, e.printed, e.sigma, e.table3, e.fitted] for e in fit.entries],
              overwrite=overwrite)
    labels = [f"{e.case} {e.quantity} {e.cad_leg}" for e in fit.entries]
    sigma = np.array([e.sigma for e in fit.entries])
    png = plots.write_residual_bars(out / "cad_fit_residuals.png", labels,
                                    {"Table 3 model": np.array([e.table3_residual for e in fit.entries]) / sigma,
                                     "fitted CAD model": np.array([e.fit_residual for e in fit.entries]) / sigma},
                                    "Tables 5-6: residuals of the Table 3 and the fitted CAD model", overwrite)
    return ["### What the paper's CAD model was (a fitted hypothesis; Table 3 stays the default)", "",
            "Weighted least squares over every printed F_z, M_z and bending magnitude (`pressfit tables --cad-fit`;"
            " method in `pressfit/studies/cad_fit.py`).", "", text, f"![residuals]({png.name})", ""]


def _worst_case(machine: Machine, env: workspace_envelope.LoadEnvelope) -> SceneCase:
    """The nonlinear equilibrium at the envelope's largest axial leg force (its pose and load)."""
    name, leg, pose, load = workspace_envelope.worst_axial(env)
    return _scene_case(f"worst envelope pose ({name.removesuffix('_n')}, leg {leg})",
                       solve_equilibrium(machine, pose, load))


def _scene_case(title: str, eq: Equilibrium) -> SceneCase:
    """A 3D-view case labelled with its pose (m) and plate force (N)."""
    return SceneCase(f"{title}: pose ({', '.join(f'{v:.3f}' for v in eq.pose_m)}) m, force "
                     f"({', '.join(f'{v:.0f}' for v in eq.load[:3])}) N", eq)


def _preload_section(machine: Machine, out: Path, overwrite: bool, res: Resolution, parts: Parts) -> list[str]:
    """Clearance vs preload at pose A and off-centre: the stiffness that preload buys back."""
    md = ["## 5. Clearance and preload", "",
          "Axial play g at each cardan (smoothed dead zone, contact stiffness from the machine file), "
          "actuator preload a4 along v_p (force mode), then the press load 0 ... 700 N (+y). The critical "
          "preload is the smallest that keeps every cardan closed up to 700 N.", ""]
    preloads = list(res.preloads_n)
    if machine.redundancy == 0:
        preloads = [0.0]
        md += [f"{machine.name} has {len(machine.legs)} legs: no redundant actuation, so no internal preload; the "
               "study shows the clearance alone.", ""]
    studies = []
    poses = (("pose_A", (0.0, 0.72, 0.0)), ("off_centre", (0.2, 0.6, -0.2)))[:res.preload_poses]
    for name, pose in poses:
        study = preload_study.preload_study(machine, pose, [0.0, 10e-6, 20e-6, 40e-6], preloads, 700.0,
                                        res.preload_load_steps, progress=False)
        studies.append((name, study))
        paths = maps.write_preload_study(study, out / "preload" / name, overwrite, figures=res.figures)
        md += [
            f"### {name.replace('_', ' ')} {list(pose)} m",
            "",
            "```",
            preload_study.format_answers(study),
            "```",
            "",
        ]
        md += [f"![{p.name}](preload/{name}/{p.name})" for p in paths if p.suffix == ".png"] + [""]
    parts["studies"] = studies
    return md

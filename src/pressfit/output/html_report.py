"""``report.html``: the interactive, offline page of ``pressfit report`` (beside ``report.md``).

Why plotly: its 3D traces (mesh3d tubes and boxes, scatter3d markers) rotate, zoom and hover in the
browser with WebGL; buttons, dropdowns and sliders restyle a figure without a server or custom
JavaScript; figures are plain JSON built from Python; and its JavaScript bundle is one offline file that
needs no build step. The bundle is written once beside the page as ``plotly.min.js`` and loaded by a
relative path, so the page itself names no external URL and works from ``file://`` without a network.

The numbers shown are those the report computed (and wrote to its CSV/JSON files): tables are rendered
from exactly the records written to the JSON files they link to (every cell carries its JSON value in
``data-value``); the 3D view is :mod:`pressfit.output.scene3d`. Table cells show floats with 4
significant digits; headers sort a table on click (a few lines of inline JavaScript).
"""

from __future__ import annotations

import html
import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import plotly.graph_objects as go
from plotly.colors import qualitative
from plotly.offline import get_plotlyjs
from plotly.subplots import make_subplots

from pressfit.description.monitor_windows import Envelope, MaxForce, Threshold, Window
from pressfit.output.curve_files import BOARD_PIN_COLUMNS, JOINT_CURVE_KEYS
from pressfit.output.files import write_text
from pressfit.output.maps import kinematic_fields
from pressfit.output.scene3d import SceneCase, scene_figure
from pressfit.studies.cycle_study import FACTOR_LABELS
from pressfit.studies.paper_tables import TABLES, TableEntry, case_table, shown_value
from pressfit.studies.preload_study import format_answers
from pressfit.studies.workspace_envelope import LEG_QUANTITIES, PLATE_QUANTITIES

if TYPE_CHECKING:
    from pressfit.description.machine import Machine
    from pressfit.dynamics.cycle import CycleResult
    from pressfit.dynamics.insertion import InsertionResult
    from pressfit.geometry.interference import SweepResult
    from pressfit.kinematics.workspace import PlaneMap
    from pressfit.mechanics.condensed import StiffnessMaps
    from pressfit.studies.compare import Comparison
    from pressfit.studies.joint_curves import JointCurves
    from pressfit.studies.preload_study import PreloadStudy
    from pressfit.studies.workspace_envelope import LoadEnvelope

Record = dict[str, object]
REL_ERROR_FORMULA = "relative error = (pressfit linear - paper) / |paper|, in the paper's axes and signs"
_CONFIG = {"displaylogo": False, "responsive": True}
_PALETTE = qualitative.Plotly
_DASHES = ("solid", "dash", "dot", "dashdot", "longdash")
_STYLE = """body{font-family:system-ui,sans-serif;margin:1.5em auto;max-width:1200px;padding:0 1em;color:#222}
h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}p.how{color:#444;max-width:60em}
table{border-collapse:collapse;font-size:.85em;margin:.5em 0}td,th{border:1px solid #ccc;padding:2px 6px}
th{background:#eef;cursor:pointer;user-select:none}th:hover{background:#dde}td{text-align:right}
.plot{width:100%;min-height:450px}pre{background:#f6f6f6;padding:.6em;font-size:.85em;overflow-x:auto}"""
_SORT_JS = """document.querySelectorAll("table.sortable th").forEach(th => th.addEventListener("click", () => {
  const body = th.closest("table").tBodies[0], col = th.cellIndex, dir = th.dataset.dir === "asc" ? -1 : 1;
  th.dataset.dir = dir > 0 ? "asc" : "desc";
  const key = r => { const v = JSON.parse(r.cells[col].dataset.value);
    return typeof v === "number" ? [0, v] : [1, String(v)]; };
  Array.from(body.rows).sort((a, b) => { const x = key(a), y = key(b);
    return dir * (x[0] - y[0] || (x[1] < y[1] ? -1 : x[1] > y[1] ? 1 : 0)); }).forEach(r => body.appendChild(r));
}));"""


@dataclass(frozen=True, kw_only=True)
class ReportContent:
    """Everything ``write_report`` computed that the page shows (SI), with the JSON records of its tables."""

    machine: Machine
    scene: list[SceneCase]  # the worst envelope pose first, then the paper's cases
    tables: list[Record]  # tables.json: TableEntry.as_dict() of Tables 5-6
    plane_maps: list[PlaneMap]
    required_square_m: np.ndarray  # (4, 2) corners (x, z) of the required square (kinematics.workspace.square_corners)
    envelope: LoadEnvelope
    envelope_table: list[Record]  # envelope/load_envelope.json
    stiffness: list[StiffnessMaps]
    preload: list[tuple[str, PreloadStudy]]  # (directory name under preload/, study)
    interference: SweepResult
    interference_table: list[Record]  # summary.json "interference", one record per pair kind
    insertion: tuple[InsertionResult, InsertionResult] | None = None  # the paper's scenario with / without limiter
    cycle: CycleResult | None = None  # the shipped board (cycle/cycle.json)
    cycle_front: Record | None = None  # a throughput study's summary.json (cycle/study_summary.json), if given
    comparison: Comparison | None = None  # the machines compared (compare/compare.json)
    joint: JointCurves | None = None  # the joint and its press curve (joint/joint.json)


def cell_text(value: object) -> str:
    """How a table cell shows a JSON value: floats with 4 significant digits, others as text."""
    if isinstance(value, float):
        return f"{value:.4g}"
    return "" if value is None else str(value)


def relative_error_text(record: Record) -> str:
    """The relative-error cell of a Tables 5-6 record: a signed percentage, or why there is none."""
    err = record["relative_error"]
    if err is not None:
        return f"{100 * float(err):+.2f} %"
    return "~0 both" if record["compared"] else "listed (frame)"


def _table(table_id: str, columns: Sequence[tuple[str, str]], records: list[Record],
           texts: dict[str, Callable[[Record], str]] | None = None) -> str:
    """A sortable table of JSON records: columns (key, header); ``texts`` overrides a column's cell text. A
    non-finite number is JSON null and an empty cell, as the JSON files write it (``output.files.to_json``)."""
    texts = texts or {}
    head = "".join(f"<th>{html.escape(h)}</th>" for _, h in columns)
    rows = []
    for r in records:
        values = {k: None if isinstance(r[k], float) and not np.isfinite(r[k]) else r[k] for k, _ in columns}
        cells = [f"<td data-key=\"{k}\" data-value=\"{html.escape(json.dumps(values[k]))}\">"
                 f"{html.escape(texts[k](r) if k in texts else cell_text(values[k]))}</td>" for k, _ in columns]
        rows.append("<tr>" + "".join(cells) + "</tr>")
    return (f'<table class="sortable" id="{table_id}"><thead><tr>{head}</tr></thead><tbody>'
            + "\n".join(rows) + "</tbody></table>")


class _Page:
    """Collects sections and figures; figures get sequential div ids."""

    def __init__(self) -> None:
        self.parts: list[str] = []
        self.figures = 0

    def section(self, anchor: str, title: str, how: str) -> None:
        self.parts.append(f'<h2 id="{anchor}">{html.escape(title)}</h2><p class="how">{how}</p>')

    def figure(self, fig: go.Figure) -> None:
        div = f"fig-{self.figures}"
        self.figures += 1
        spec = fig.to_json().replace("</", "<\\/")
        self.parts.append(f'<div class="plot" id="{div}"></div><script>(function(){{const f = {spec};'
                          f'Plotly.newPlot("{div}", f.data, f.layout, {json.dumps(_CONFIG)});}})();</script>')

    def add(self, text: str) -> None:
        self.parts.append(text)


def _links(*paths: str) -> str:
    return "<p>Numbers: " + ", ".join(f'<a href="{html.escape(p)}">{html.escape(p)}</a>' for p in paths) + "</p>"


def _map_figure(title: str, x_m: np.ndarray, z_m: np.ndarray, panels: dict[str, tuple[np.ndarray, str]],
                outline: np.ndarray | None = None) -> go.Figure:
    """Heatmaps over the x-z plane (indexed [i_z, i_x]), one shown at a time (a dropdown), NaN blank; values
    travel as float32 (7 significant digits, a quarter of the page size of JSON text)."""
    fig = go.Figure()
    names = list(panels)
    for k, (name, (values, unit)) in enumerate(panels.items()):
        fig.add_heatmap(x=x_m, y=z_m, z=np.asarray(values, dtype=np.float32), visible=k == 0, name=name,
                        colorscale="Viridis", colorbar={"title": {"text": unit}},
                        hovertemplate="x = %{x:.3f} m, z = %{y:.3f} m<br>%{z:.4g} " + unit + "<extra></extra>")
    if outline is not None:
        ring = np.vstack([outline, outline[:1]])
        fig.add_scatter(x=ring[:, 0], y=ring[:, 1], mode="lines", line={"color": "magenta", "dash": "dash"},
                        name="required square", hoverinfo="skip")
    extra = [True] if outline is not None else []
    fig.update_layout(title={"text": title}, height=520, xaxis={"title": {"text": "x [m]"}},
                      yaxis={"title": {"text": "z [m]"}, "scaleanchor": "x"}, showlegend=False,
                      updatemenus=[{"x": 0.0, "y": 1.12, "xanchor": "left", "buttons": [
                          {"label": n, "method": "update",
                           "args": [{"visible": [j == k for j in range(len(names))] + extra}]}
                          for k, n in enumerate(names)]}])
    return fig


def _scene_section(page: _Page, c: ReportContent) -> None:
    page.section("scene", "1. The loaded machine in 3D",
                 "Base, plate, legs (cylinder and stem tubes, radii of the interference model) and cardans "
                 "(diamonds) at the selected pose and load, from the geometrically nonlinear equilibrium. The "
                 "buttons colour the legs by axial force (red tension, blue compression), torsion or bending "
                 "magnitude; the slider magnifies the deflection (legs run straight from the base cardans to the "
                 "displaced plate cardans). Hover a leg for its section resultants; drag to turn the machine.")
    page.figure(scene_figure(c.machine, c.scene))


def _tables_section(page: _Page, c: ReportContent) -> None:
    page.section("tables", "2. The paper's Tables 5 and 6",
                 "Actuator-section resultants of the paper's cases A, B and C (700 N press reaction, +y) beside "
                 f"pressfit's linear (rigid-limit) and nonlinear solutions; {REL_ERROR_FORMULA}. Frame-dependent "
                 "entries (F_x, F_y, M_x, M_y) are listed without an error. Click a header to sort.")
    cols = [("case", "case"), ("quantity", "component"), ("cad_leg", "CAD leg"), ("kinematic_leg", "kin. leg"),
            ("paper", "paper"), ("linear", "pressfit linear"), ("relative_error", "rel. error"),
            ("nonlinear", "pressfit nonlinear")]
    entries = [TableEntry(**{**r, "relative_error": math.nan if r["relative_error"] is None else
                                    r["relative_error"]}) for r in c.tables]
    for table, title in TABLES:  # as the paper prints them: per case, components by leg
        for case in dict.fromkeys(e.case for e in entries):
            header, rows = case_table(entries, case, table)
            page.add(f'<h3>{html.escape(f"{table}: {title}, {case}")}</h3><table id="{table.replace(" ", "-")}-'
                     f'{html.escape(case)}"><thead><tr>' + "".join(f"<th>{html.escape(h)}</th>" for h in header)
                     + "</tr></thead><tbody>" + "\n".join("<tr>" + "".join(f"<td>{html.escape(x)}</td>" for x in r)
                                                         + "</tr>" for r in rows) + "</tbody></table>")
    scale = {(e.case, e.table): max(max(abs(x.paper), abs(x.linear)) for x in entries
                                    if (x.case, x.table) == (e.case, e.table)) for e in entries}
    shown = {k: (lambda r, k=k: shown_value(r[k], scale[r["case"], "Table 5" if r["quantity"][0] == "F"
                                                                 else "Table 6"]))
             for k in ("paper", "linear", "nonlinear")}
    page.add("<h3>Every entry (sortable)</h3>")
    page.add(_table("tables-5-6", cols, c.tables, {"relative_error": relative_error_text, **shown}))
    page.add(_links("tables.json", "tables.csv", "tables.md"))


def _kinematics_section(page: _Page, c: ReportContent) -> None:
    page.section("kinematics", "3. Kinematic maps (paper section 4.1)",
                 "Dexterity n (equation 4), force indices F_x, F_y, F_z (equations 6-8) and leg 1's rates "
                 "dl_1/dh (equations 2-3) over the x-z plane; the dashed square is the required workspace. "
                 "Choose the map in the dropdown; blank where the pose is outside the joint limits.")
    for pm in c.plane_maps:
        page.figure(_map_figure(f"kinematic maps at y_h = {pm.y_m:g} m", pm.x_m, pm.z_m, kinematic_fields(pm),
                                c.required_square_m))
    page.add(_links(*[f"kinematics/maps_y{pm.y_m:.3f}.csv" for pm in c.plane_maps], "kinematics/summary.json"))


def _envelope_section(page: _Page, c: ReportContent) -> None:
    env = c.envelope
    page.section("envelope", "4. Workspace load envelope",
                 f"The worst leg loads and plate motions over the required square at y_h = {env.y_m.min():g} ... "
                 f"{env.y_m.max():g} m under {len(env.loads)} press loads (exact condensed linear model). The bars "
                 "give each leg's worst value (hover for the pose and load where it occurs), the maps the worst "
                 "value over heights, loads and legs at each x-z point. The 3D view opens at the largest axial force.")
    fig = go.Figure()
    names = list(LEG_QUANTITIES)
    for k, name in enumerate(names):
        e = env.entries[name]
        fig.add_bar(x=[f"leg {i + 1}" for i in range(len(e.value))], y=e.value, visible=k == 0, name=name,
                    customdata=np.hstack([e.pose_m, e.load_n]),
                    hovertemplate="%{y:.4g} " + LEG_QUANTITIES[name][0] + "<br>pose (%{customdata[0]:.3f}, "
                    "%{customdata[1]:.3f}, %{customdata[2]:.3f}) m<br>load (%{customdata[3]:.1f}, %{customdata[4]:.1f},"
                    " %{customdata[5]:.1f}) N<extra></extra>")
    fig.update_layout(title={"text": "worst value per leg"}, height=420, yaxis={"title": {"text": "value (unit in the "
                                                                                                  "dropdown)"}},
                      updatemenus=[{"x": 0.0, "y": 1.15, "xanchor": "left", "buttons": [
                          {"label": f"{n} [{LEG_QUANTITIES[n][0]}]", "method": "update",
                           "args": [{"visible": [j == k for j in range(len(names))]}]} for k, n in enumerate(names)]}])
    page.figure(fig)
    units = {**LEG_QUANTITIES, **PLATE_QUANTITIES}
    page.figure(_map_figure("worst value over heights, loads and legs", env.x_m, env.z_m,
                            {f"worst_{k}": (m, units[k][0]) for k, m in env.maps.items()}))
    cols = [(k, k) for k in c.envelope_table[0]]
    page.add(_table("envelope", cols, c.envelope_table))
    page.add(_links("envelope/load_envelope.json", "envelope/load_envelope.csv"))


def _stiffness_section(page: _Page, c: ReportContent) -> None:
    page.section("stiffness", "5. Stiffness maps",
                 "Plate stiffness for a force at the plate centre (plate free to tilt; lateral = the weakest "
                 "horizontal direction), and the tilt and horizontal drift under the press load, over the required "
                 "square at each height (condensed linear model). Choose the map in the dropdown.")
    for s in c.stiffness:
        page.figure(_map_figure(f"stiffness at y = {s.y_m:g} m", s.x_m, s.z_m, s.fields()))
    page.add(_links(*[f"stiffness/stiffness_maps_y{round(s.y_m * 1000):d}mm.csv" for s in c.stiffness]))


def _preload_section(page: _Page, c: ReportContent) -> None:
    page.section("preload", "6. Clearance and preload",
                 "Axial play g at each cardan, actuator preload a4 along v_p, then the press load 0 ... 700 N (+y). "
                 "First: plate stiffness against preload per clearance (dashed: secant at a small load, solid: secant "
                 "at the full load; the black and dotted lines are the machine without clearance, with the cardan "
                 "contact springs and with rigid cardans). Then the load-deflection curves "
                 "(colour: preload, dash: clearance). The "
                 "critical preload is the smallest that keeps every cardan closed up to the full load.")
    for name, st in c.preload:
        unit = "N" if st.preload_mode == "force" else "m"
        fig = go.Figure()
        for g, gap in enumerate(st.clearances_m):
            fig.add_scatter(x=st.preloads, y=st.small_load_secant_stiffness_n_per_m[g], mode="lines+markers",
                            line={"dash": "dash"}, name=f"g = {gap * 1e6:g} um, secant at {st.small_load_n:g} N",
                            legendgroup=str(g))
            fig.add_scatter(x=st.preloads, y=st.press_secant_stiffness_n_per_m[g], mode="lines+markers",
                            name=f"g = {gap * 1e6:g} um, secant at {st.loads_n[-1]:g} N", legendgroup=str(g))
        fig.add_hline(y=st.no_clearance_contact_stiffness_n_per_m, line={"color": "black", "width": 1},
                      annotation_text="no clearance, cardan contact springs in series")
        fig.add_hline(y=st.rigid_cardan_stiffness_n_per_m, line={"color": "gray", "width": 1, "dash": "dot"},
                      annotation_text="no clearance, rigid cardans")
        fig.update_layout(title={"text": f"{name}: pose {st.pose_m.tolist()} m"}, height=440,
                          xaxis={"title": {"text": f"preload a4 [{unit}]"}},
                          yaxis={"title": {"text": "stiffness [N/m]"}, "type": "log"})
        page.figure(fig)
        curves = go.Figure()
        for g, p in np.ndindex(len(st.clearances_m), len(st.preloads)):  # colour: preload, dash: clearance
            curves.add_scatter(x=st.deflection_m[g, p] * 1e6, y=st.loads_n, mode="lines", legendgroup=str(g),
                               line={"color": _PALETTE[p % len(_PALETTE)], "dash": _DASHES[g % len(_DASHES)]},
                               name=f"g = {st.clearances_m[g] * 1e6:g} um, a4 = {st.preloads[p]:g} {unit}")
        curves.update_layout(title={"text": f"{name}: load-deflection (click the legend to hide curves)"},
                             height=440, xaxis={"title": {"text": "deflection along the load [um]"}},
                             yaxis={"title": {"text": "load [N]"}})
        page.figure(curves)
        page.add(f"<pre>{html.escape(format_answers(st))}</pre>")
        page.add(_links(f"preload/{name}/preload_study.json", f"preload/{name}/preload_study.csv"))


def _interference_section(page: _Page, c: ReportContent) -> None:
    sw = c.interference
    page.section("interference", "7. Leg interference",
                 f"Minimum signed distance (Coal) between legs, plate, base and extra bodies over the required "
                 f"workspace; a pair passes above the margin of {sw.margin_m * 1000:g} mm "
                 f"({'PASS' if sw.passed else 'FAIL'}). The map gives the smallest distance over all pairs at each "
                 "pose; the table the smallest per pair kind.")
    if sw.grid_axes_m is not None:
        xs, ys, zs = sw.grid_axes_m
        d = sw.min_distance_m.reshape(len(ys), len(zs), len(xs))
        page.figure(_map_figure("minimum distance over pairs", xs, zs,
                                {f"y_h = {y:.3f} m": (d[k], "m") for k, y in enumerate(ys)}))
    cols = [("kind", "pair kind"), ("distance_m", "min distance [m]"), ("pair", "pair"), ("pose_m", "pose [m]")]
    page.add(_table("interference", cols, c.interference_table,
                    {"pose_m": lambda r: ", ".join(f"{v:.4g}" for v in r["pose_m"])}))
    page.add(_links("summary.json", "interference/interference_pairs.csv", "interference/interference_poses.csv"))


def _insertion_section(page: _Page, c: ReportContent) -> None:
    if c.insertion is None:
        return
    page.section("insertion", "8. Pin insertion (paper section 4.2, Figures 12-14)",
                 "The paper's scenario (cases/paper/insertion.toml): force-limited position control over four 40 Hz "
                 "force-controlled actuators, the machine's compliance in series with an elastic pin-board contact. "
                 "The contact force against time with and without the force limiter (dashed: the limit); the table "
                 "gives the summary of both runs.")
    fig = go.Figure()
    for run, name in zip(c.insertion, ("with the limiter", "without the limiter")):
        fig.add_scatter(x=run.column("time_s"), y=run.column("contact_force_n"), mode="lines", name=name)
    fig.add_hline(y=c.insertion[0].summary["force_limit_n"], line={"dash": "dash", "color": "black"})
    fig.update_layout(height=420, xaxis={"title": {"text": "time [s]"}}, yaxis={"title": {"text": "contact force [N]"}})
    page.figure(fig)
    keys = ("peak_contact_force_n", "overshoot_n", "steady_insertion_force_n", "steady_insertion_depth_m",
            "positioning_error_m", "settling_time_s")
    shown = [{k: "did not settle" if run.summary[k] is None else run.summary[k] for k in keys} for run in c.insertion]
    records = [{"quantity": k, "with_limiter": shown[0][k], "without_limiter": shown[1][k]} for k in keys]
    page.add(_table("insertion", [("quantity", "quantity (SI)"), ("with_limiter", "with the limiter"),
                                  ("without_limiter", "without")], records))
    page.add(_links("insertion/simulation.json", "insertion/simulation.csv"))


CYCLE_PIN_COLUMNS = (("index", "pin"), ("x_m", "x [m]"), ("z_m", "z [m]"), ("first_contact_time_s", "contact [s]"),
                     ("peak_contact_force_n", "peak [N]"), ("steady_insertion_force_n", "steady [N]"),
                     ("overshoot_n", "overshoot [N]"), ("tool_lateral_error_at_first_contact_m", "alignment [m]"),
                     ("settling_time_s", "settling [s]"), ("passed", "passed"))
CYCLE_DRIVE_COLUMNS = (("leg", "drive"), ("peak_force_n", "peak force [N]"), ("rms_force_n", "RMS force [N]"),
                       ("rms_force_without_preload_n", "RMS force, a4 = 0 [N]"),
                       ("peak_speed_m_per_s", "peak speed [m/s]"), ("peak_power_w", "peak power [W]"),
                       ("positive_energy_j", "energy + [J]"), ("regenerative_energy_j", "energy - [J]"))
CYCLE_FRONT_COLUMNS = (("sample", "sample"), *FACTOR_LABELS.items(), ("cycle_time_s", "cycle time [s]"),
                       ("worst_alignment_error_m", "worst alignment [m]"), ("worst_overshoot_n", "worst overshoot [N]"),
                       ("within_limits", "within the limits"))


def _cycle_section(page: _Page, c: ReportContent) -> None:
    if c.cycle is None:
        return
    s = c.cycle.summary
    page.section("cycle", "9. The shipped board's work cycle",
                 f"cases/paper/board.toml (<code>pressfit cycle</code>, model {html.escape(str(s['model']))}, "
                 f"{s['pin_count']} pins, a {c.cycle.plan.scenario.simulation.time_step_s * 1e3:g} ms step; "
                 "<code>pressfit report --quick</code> runs its first pins only, with a short "
                 f"dwell): cycle time {s['cycle_time_s']:.4g} s, {s['pins_per_minute']:.4g} pins per minute, "
                 f"{s['pins_passed']} of {s['pin_count']} pins pass. The contact force of every pin over the cycle "
                 "(dashed: the pins' force limits), the per-pin figures and the drive sizing over the cycle (with "
                 f"a4 = 0 beside: the preload's cost); energy balance residual "
                 f"{100 * s['energy_balance_residual']:.2g}% of the drives' gross work.")
    t, force, pin = c.cycle.column("time_s"), c.cycle.column("contact_force_n"), c.cycle.column("pin")
    fig = go.Figure()
    for record in s["pins"]:
        shown = np.where(pin == record["index"], force, np.nan)
        fig.add_scatter(x=t, y=shown, mode="lines", name=f"pin {record['index']}", connectgaps=False)
    for limit in sorted({p["force_limit_n"] for p in s["pins"]}):
        fig.add_hline(y=limit, line={"dash": "dash", "color": "black"})
    fig.update_layout(height=420, xaxis={"title": {"text": "time [s]"}}, yaxis={"title": {"text": "contact force [N]"}})
    page.figure(fig)
    page.add(_table("cycle-pins", CYCLE_PIN_COLUMNS, [{k: p[k] for k, _ in CYCLE_PIN_COLUMNS} for p in s["pins"]]))
    page.add(_table("cycle-drives", CYCLE_DRIVE_COLUMNS,
                    [{k: d.get(k) for k, _ in CYCLE_DRIVE_COLUMNS} for d in s["drives"]]))
    page.add(_links("cycle/cycle.json", "cycle/cycle.csv"))
    if c.cycle_front is not None:
        f = c.cycle_front
        fig = go.Figure()
        rows = f["front"]
        fig.add_scatter(x=[r["cycle_time_s"] for r in rows], y=[r["worst_alignment_error_m"] for r in rows],
                        mode="markers", marker={"size": 10, "color": [r["worst_overshoot_n"] for r in rows],
                                                "colorbar": {"title": {"text": "worst overshoot [N]"}}},
                        name="Pareto front")
        fig.update_layout(height=420, title={"text": f"throughput study: the Pareto front ({f['samples']} samples)"},
                          xaxis={"title": {"text": "cycle time [s]"}},
                          yaxis={"title": {"text": "worst alignment error [m]"}})
        page.figure(fig)
        page.add(_table("cycle-front", CYCLE_FRONT_COLUMNS, [{k: r[k] for k, _ in CYCLE_FRONT_COLUMNS} for r in rows]))
        page.add(_links("cycle/study_summary.json"))


COMPARE_COLUMNS = (("name", "machine"), ("legs", "legs"), ("worst_drive_force_n", "worst drive force [N]"),
                   ("worst_bending_nm", "worst member bending [N m]"),
                   ("weakest_stiffness_worst_n_per_m", "weakest stiffness, worst [N/m]"),
                   ("vertical_stiffness_worst_n_per_m", "vertical stiffness, worst [N/m]"),
                   ("tilt_worst_rad", "tilt under 700 N, worst [rad]"),
                   ("first_frequency_lowest_hz", "first frequency, lowest [Hz]"),
                   ("moving_mass_kg", "moving mass [kg]"),
                   ("lost_motion_m", "lost motion, 20 um play [m]"),
                   ("lost_motion_preloaded_m", "lost motion, critical preload [m]"),
                   ("critical_preload_worst_n", "critical preload, worst pose [N]"))


def _compare_section(page: _Page, c: ReportContent) -> None:
    if c.comparison is None:
        return
    machines = [m.to_dict() for m in c.comparison.machines]
    page.section("compare", "10. The machines compared",
                 "<code>pressfit compare</code>: the report's machine beside Tsai's 3-UPU, the Cartesian gantry of the "
                 "paper's Figure 2 and the 4-UPU turned 45 degrees, each over its required box under the 700 N press "
                 "load and its 5 degree cone; the paper's claims decided with the numbers: "
                 + "; ".join(f"<b>{html.escape(x.verdict)}</b> against {html.escape(x.baseline)}: "
                             f"{html.escape(x.claim)} ({html.escape(x.evidence)})" for x in c.comparison.claims) + ".")
    fig = make_subplots(rows=1, cols=4, subplot_titles=("worst drive force [N]", "worst member bending [N m]",
                                                        "weakest tool stiffness [N/m]", "first frequency [Hz]"))
    for col, key in enumerate(("worst_drive_force_n", "worst_bending_nm", "weakest_stiffness_worst_n_per_m",
                               "first_frequency_lowest_hz"), start=1):
        fig.add_bar(x=[m["name"] for m in machines], y=[m[key] for m in machines], row=1, col=col, showlegend=False)
    fig.update_layout(height=420)
    page.figure(fig)
    page.add(_table("compare-machines", COMPARE_COLUMNS, [{k: m[k] for k, _ in COMPARE_COLUMNS} for m in machines]))
    page.add(_links("compare/compare.json", "compare/compare.csv"))


JOINT_PIN_HEADERS = {"index": "pin", "x_m": "x [m]", "z_m": "z [m]",
                     "machine_compliance_along_press_m_per_n": "compliance along the press [m/N]",
                     "peak_force_n": "peak force [N]", "sensed_minus_true_depth_at_peak_m": "sensed - true at peak [m]",
                     "max_depth_m": "true depth at the stop [m]", "force_limit_n": "force limit [N]"}


def _joint_section(page: _Page, c: ReportContent) -> None:
    if c.joint is None:
        return
    j, mm = c.joint, 1e3
    page.section("joint", "11. The joint and its press curve",
                 f"Left: {html.escape(j.case_name)} (cases/paper/insertion_compliant_pin.toml), the press curve "
                 "predicted quasi-statically (the pins' law in series with the machine's compliance at the pin pose) "
                 "against the true depth and against the sensed depth the drives' encoders record, over its tolerance "
                 f"band (a serial Monte Carlo of {j.study.band.samples} samples; <code>pressfit study curve</code> "
                 "runs the design band) and the monitor's windows derived from it (sensed depth). Right: every pin of "
                 f"{html.escape(j.board_name)} pressed with the board's contact law at its own pose up to its force "
                 "limit: they share one true curve; each pin's force against its sensed minus true depth (the "
                 "press's deflection, the skew of its sensed curve), set by the machine's compliance along the press "
                 "at its pose (table).")
    fig = make_subplots(rows=1, cols=2, subplot_titles=("predicted curve, band and windows",
                                                        "the board's pins: the press's deflection"))
    band = j.study.band
    lo, hi = band.force_n[0], band.force_n[-1]
    fig.add_scatter(x=band.grid_m * mm, y=lo, mode="lines", line={"width": 0}, showlegend=False, row=1, col=1,
                    hoverinfo="skip")
    fig.add_scatter(x=band.grid_m * mm, y=hi, mode="lines", line={"width": 0}, fill="tonexty",
                    fillcolor="rgba(128,128,128,0.3)", row=1, col=1,
                    name=f"band q{band.quantiles[0]:g}-q{band.quantiles[-1]:g} ({band.samples} samples)")
    for el in j.windows.elements:
        if isinstance(el, Window):
            fig.add_scatter(x=np.array([el.x_min_m, el.x_max_m, el.x_max_m, el.x_min_m, el.x_min_m]) * mm,
                            y=[el.y_min_n, el.y_min_n, el.y_max_n, el.y_max_n, el.y_min_n], mode="lines",
                            line={"color": "green"}, name=f"window '{el.name}'", row=1, col=1)
        elif isinstance(el, Threshold):
            fig.add_scatter(x=np.array([el.x_min_m, el.x_max_m]) * mm, y=[el.force_n] * 2, mode="lines",
                            line={"color": "purple" if el.mode == "must_cross" else "orange"},
                            name=f"threshold '{el.name}' ({el.mode.replace('_', ' ')})", row=1, col=1)
        elif isinstance(el, Envelope):
            for force, show in ((el.lower_force_n, True), (el.upper_force_n, False)):
                fig.add_scatter(x=np.array(el.displacement_m) * mm, y=force, mode="lines", showlegend=show,
                                line={"color": "royalblue", "width": 1}, legendgroup="envelope",
                                name=f"envelope '{el.name}'", row=1, col=1)
        elif isinstance(el, MaxForce):
            fig.add_hline(y=el.force_n, line={"dash": "dot", "color": "red"}, row=1, col=1)
    fig.add_scatter(x=j.curve.depth_m * mm, y=j.curve.force_n, mode="lines", line={"dash": "dash"},
                    name="nominal, true depth", row=1, col=1)
    fig.add_scatter(x=j.curve.sensed_depth_m * mm, y=j.curve.force_n, mode="lines", line={"color": "black"},
                    name="nominal, sensed depth", row=1, col=1)
    for p in j.board:
        fig.add_scatter(x=(p.curve.sensed_depth_m - p.curve.depth_m) * 1e6, y=p.curve.force_n, mode="lines",
                        name=f"pin {p.index} ({p.x_m:.2f}, {p.z_m:.2f}) m", row=1, col=2)
    fig.update_layout(height=520)
    fig.update_xaxes(title_text="depth [mm] (band and windows: sensed)", row=1, col=1)
    fig.update_xaxes(title_text="sensed minus true depth [um] (the press's deflection)", row=1, col=2)
    for col in (1, 2):
        fig.update_yaxes(title_text="force [N]", row=1, col=col)
    page.figure(fig)
    summary = j.curve.summary()
    page.add(_table("joint-curve", [("quantity", "quantity (SI)"), ("value", "value")],
                    [{"quantity": k, "value": summary[k]} for k in JOINT_CURVE_KEYS]))
    page.add(_table("joint-board", [(k, JOINT_PIN_HEADERS[k]) for k in BOARD_PIN_COLUMNS],
                    [{k: p.summary()[k] for k in BOARD_PIN_COLUMNS} for p in j.board]))
    page.add(_links("joint/joint.json", "joint/windows.json", "joint/curve.csv", "joint/band.csv",
                    "joint/board_pins.csv", "joint/board_curves.csv"))


def write_html_report(out_dir: Path | str, content: ReportContent, overwrite: bool = False) -> Path:
    """Write ``report.html`` and ``plotly.min.js`` (the offline plotly bundle) into out_dir; returns the page."""
    out = Path(out_dir)
    page = _Page()
    m = content.machine
    page.add(f"<h1>pressfit report: {html.escape(m.name)}</h1><p>Machine file: <code>{html.escape(m.source)}</code>. "
             "SI units throughout. The same numbers as <a href=\"report.md\">report.md</a>, interactive.</p>")
    for section in (_scene_section, _tables_section, _kinematics_section, _envelope_section, _stiffness_section,
                    _preload_section, _interference_section, _insertion_section, _cycle_section, _compare_section,
                    _joint_section):
        section(page, content)
    write_text(out / "plotly.min.js", get_plotlyjs(), overwrite)
    doc = (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>pressfit report: "
           f"{html.escape(m.name)}</title><style>{_STYLE}</style><script src=\"plotly.min.js\"></script></head>"
           "<body>\n" + "\n".join(page.parts) + f"\n<script>{_SORT_JS}</script></body></html>\n")
    return write_text(out / "report.html", doc, overwrite)

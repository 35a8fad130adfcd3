"""report.html in a real headless browser (Debian's chromium driven by Playwright), and the 3D view's
geometry against the closed-form kinematics.

The browser is never downloaded: Playwright launches /usr/bin/chromium. Without it these tests FAIL
(they never skip); install it with `apt-get install -y chromium` (the README's test command does).
"""

import io
import json
import shutil
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from PIL import Image
from study_front import STUDY_FRONT

from pressfit.mechanics.statics import solve_equilibrium
from pressfit.output.scene3d import MAGNIFICATIONS, SceneCase, scene_figure

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]


@pytest.fixture(scope="module")
def report_dir(quick_report):
    """The suite's one quick report (tests/conftest.py), with a cycle study's front in its board section."""
    return quick_report


@pytest.fixture(scope="module")
def browser():
    if not Path(CHROMIUM).exists() or shutil.which("chromium") is None:
        pytest.fail("chromium is missing: install Debian's package with `apt-get install -y chromium` "
                    "(the README's test command does this); the browser tests never skip", pytrace=False)
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


@pytest.fixture(scope="module")
def page(browser, report_dir):
    """The report loaded from file://, with its console errors, page errors and requests recorded."""
    pg = browser.new_page(viewport={"width": 1300, "height": 900})
    pg.errors, pg.requests = [], []
    pg.on("console", lambda m: pg.errors.append(m.text) if m.type == "error" else None)
    pg.on("pageerror", lambda e: pg.errors.append(str(e)))
    pg.on("request", lambda r: pg.requests.append(r.url))
    pg.goto((report_dir / "report.html").as_uri())
    pg.wait_for_function("document.querySelectorAll('.plot').length > 0 && Array.from("
                         "document.querySelectorAll('.plot')).every(d => d._fullLayout)")
    pg.wait_for_timeout(500)  # WebGL draws after newPlot resolves
    yield pg
    pg.close()


def _pixels(png: bytes) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


def test_page_loads_offline_without_errors(page, report_dir):
    assert page.errors == []
    assert page.requests and all(u.startswith("file://") for u in page.requests), page.requests
    text = (report_dir / "report.html").read_text()
    assert "http://" not in text and "https://" not in text  # no external URL anywhere in the page
    assert '<script src="plotly.min.js">' in text and (report_dir / "plotly.min.js").stat().st_size > 1e6
    n_plots = page.evaluate("document.querySelectorAll('.plot').length")
    assert n_plots >= 8 and page.evaluate("document.querySelectorAll('.plot .main-svg').length") >= n_plots


def _new_colour_fraction(before: np.ndarray, after: np.ndarray) -> float:
    """Fraction of the pixels of ``after`` whose colour (quantised to 16 levels per channel) is absent from
    ``before``, over the left 90 % of the figure (the colour bar excluded). A re-layout that only moves
    the scene scores ~1e-6 here (measured); recolouring the legs scores ~1.5e-2."""
    def keys(img):
        q = img[:, : int(0.9 * img.shape[1])].reshape(-1, 3).astype(np.int64) // 16
        return q[:, 0] * 256 + q[:, 1] * 16 + q[:, 2]

    return float(np.mean(~np.isin(keys(after), keys(before))))


def test_3d_view_renders_and_the_colouring_toggle_changes_it(page):
    view = page.locator("#fig-0")
    before = _pixels(view.screenshot())
    colours = np.unique(before.reshape(-1, 3), axis=0)
    assert len(colours) > 500, len(colours)  # shaded tubes, plate and base: far from a blank canvas
    for label, title in (("torsion", "T "), ("bending", "|M| "), ("axial force", "N ")):
        page.locator("#fig-0 g.updatemenu-button", has_text=label).click()
        page.wait_for_timeout(500)
        after = _pixels(view.screenshot())
        assert np.any(before != after)
        assert _new_colour_fraction(before, after) > 3e-3, label  # the legs took new colours
        assert page.evaluate("document.getElementById('fig-0').layout.coloraxis.colorbar.title.text").startswith(title)
        before = after


def _rows(page, table_id):
    return page.evaluate(f"Array.from(document.querySelectorAll('#{table_id} tbody tr')).map(r => "
                         "Array.from(r.cells).map(c => [c.dataset.key, c.dataset.value, c.textContent]))")


def _text(v):
    """The test's own statement of the page's format: floats to 4 significant digits, a missing value (JSON null)
    as an empty cell, others as text."""
    return f"{v:.4g}" if isinstance(v, float) else "" if v is None else str(v)


def _check_table(page, table_id, records, special=None):
    rows = _rows(page, table_id)
    assert len(rows) == len(records) > 0
    for row, record in zip(rows, records):
        for key, value, text in row:
            assert json.loads(value) == record[key], (table_id, key)
            expected = special[key](record) if special and key in special else _text(record[key])
            assert text == expected, (table_id, key, text, expected)


def test_tables_5_6_cells_equal_tables_json(page, report_dir):
    records = json.loads((report_dir / "tables.json").read_text())
    assert len(records) == 3 * 7 * 4  # cases A, B, C x 7 quantities x 4 legs

    def rel(r):
        if r["relative_error"] is None:
            return "~0 both" if r["compared"] else "listed (frame)"
        return f"{100 * r['relative_error']:+.2f} %"

    def scale(r):  # the case's table's largest |paper| or |linear| entry
        return max(max(abs(x["paper"]), abs(x["linear"])) for x in records
                   if x["case"] == r["case"] and x["quantity"][0] == r["quantity"][0])

    def number(key):  # round-off (below 1e-9 of the scale) is 0, as is anything printing -0 (issue 28 item 9)
        def text(r):
            x = r[key]
            return "0" if abs(x) <= 1e-9 * scale(r) or float(f"{x:.4g}") == 0 else f"{x:.4g}"
        return text

    _check_table(page, "tables-5-6", records, {"relative_error": rel, **{k: number(k) for k in
                                                                         ("paper", "linear", "nonlinear")}})
    assert "(pressfit linear - paper) / |paper|" in page.inner_text("#tables + p")
    # as the paper prints them: per case and table, a row per CAD leg, each component's paper value then ours
    for case in ("paper-A", "paper-B", "paper-C"):
        for table, first in (("Table-5", "F_x"), ("Table-6", "M_x")):
            cells = page.locator(f"[id='{table}-{case}'] tbody tr").all_inner_texts()
            heads = page.locator(f"[id='{table}-{case}'] th").all_inner_texts()
            assert len(cells) == 4 and heads[1:3] == [f"{first} paper", f"{first} pressfit"]
            r = next(x for x in records if x["case"] == case and x["quantity"] == first and x["cad_leg"] == 1)
            assert cells[0].split("\t")[1:3] == [number("paper")(r), number("linear")(r)]
    text = page.inner_text("#tables ~ table")
    assert "e-15" not in text and "e-16" not in text


def test_envelope_and_interference_cells_equal_their_json(page, report_dir):
    _check_table(page, "envelope", json.loads((report_dir / "envelope/load_envelope.json").read_text()))
    kinds = json.loads((report_dir / "summary.json").read_text())["interference"]
    _check_table(page, "interference", [{"kind": k, **v} for k, v in kinds.items()],
                 {"pose_m": lambda r: ", ".join(f"{v:.4g}" for v in r["pose_m"])})


def test_clicking_a_header_sorts_the_table(page):
    def column():
        return [json.loads(r[4][1]) for r in _rows(page, "tables-5-6")]  # the 'paper' column

    page.locator("#tables-5-6 th", has_text="paper").first.click()
    assert column() == sorted(column())
    page.locator("#tables-5-6 th", has_text="paper").first.click()
    assert column() == sorted(column(), reverse=True)


@pytest.mark.parametrize("which", ["machine", "tsai", "five"])
def test_3d_geometry_follows_the_kinematics_and_the_solve(request, which):
    """Reference: the closed-form placement of the cardans (B_i on the base; C_i = h + u + exp(m phi) d_i,
    u and phi from the solve) and the leg radii of the machine's [collision] table, leg by leg for the 4-UPU,
    the 3-UPU and a 5-leg machine (n legs: 2n cardans, traces leg1..legn); tolerance 1e-6 m is the 0.1 um
    rounding of the page's coordinates plus float noise."""
    machine = request.getfixturevalue(which)
    pose, load = np.array([0.1, 0.6, -0.15]), np.array([30.0, 700.0, -20.0])
    eq = solve_equilibrium(machine, pose, load)
    fig = scene_figure(machine, [SceneCase("test", eq)]).to_plotly_json()
    steps = fig["layout"]["sliders"][0]["steps"]
    names = [t["name"] for t in fig["data"]]
    for m in (0.0, 1.0, 100.0):
        xyz = steps[MAGNIFICATIONS.index(m)]["args"][0]
        at = lambda name, xyz=xyz: np.c_[[xyz[a][names.index(name)] for a in "xyz"]].T
        cardans = pose + m * eq.plate_displacement_m + machine.plate_offsets_m @ pin.exp3(m * eq.plate_rotation_rad).T
        np.testing.assert_allclose(at("cardans"), np.vstack([machine.base_points_m, cardans]), atol=1e-6)
        for i in range(len(machine.legs)):
            b, c = machine.base_points_m[i], cardans[i]
            e = (c - b) / np.linalg.norm(c - b)
            v = at(f"leg{i + 1}.cylinder") - b
            radial = np.linalg.norm(v - np.outer(v @ e, e), axis=1)
            np.testing.assert_allclose(radial, machine.collision.cylinder_radius_m, atol=1e-6)
            s = v @ e
            np.testing.assert_allclose([s.min(), s.max()], [0.0, machine.cylinder.length_m], atol=1e-6)
    legs = [t for t in fig["data"] if t["name"].startswith("leg") and t["name"].endswith("cylinder")]
    assert len(legs) == len(machine.legs) and not any(n.startswith(f"leg{len(machine.legs) + 1}.") for n in names)
    np.testing.assert_allclose([t["intensity"][0] for t in legs], [leg.sections["actuator"].N for leg in eq.legs])


def test_3d_view_opens_at_the_worst_axial_force_and_the_slider_moves_the_plate(page, report_dir, machine):
    """Reference: the largest tension/compression entry of envelope/load_envelope.json gives the pose the
    view opens at; slider step 0 (magnification 0) puts the plate cardans at h + d_i exactly (to the page's
    0.1 um rounding), the last step moves them by far more than the solve's micrometres."""
    rows = [r for r in json.loads((report_dir / "envelope/load_envelope.json").read_text())
            if r["quantity"] in ("tension_n", "compression_n")]
    worst = max(rows, key=lambda r: r["value"])
    pose = np.array([worst["x_m"], worst["y_m"], worst["z_m"]])
    cardans = ("(() => { const t = document.getElementById('fig-0').data.find(d => d.name === 'cardans' && d.visible);"
               " return [t.x, t.y, t.z]; })()")
    rail = page.locator("#fig-0 .slider-rail-touch-rect")
    box = rail.bounding_box()
    rail.click(position={"x": 3, "y": box["height"] / 2})  # the first step: magnification 0
    page.wait_for_timeout(300)
    nominal = np.array(page.evaluate(cardans)).T
    np.testing.assert_allclose(nominal[4:], pose + machine.plate_offsets_m, atol=2e-7)
    np.testing.assert_allclose(nominal[:4], machine.base_points_m, atol=2e-7)
    rail.click(position={"x": box["width"] - 3, "y": box["height"] / 2})  # the last step
    page.wait_for_timeout(300)
    moved = np.array(page.evaluate(cardans)).T
    assert np.abs(moved[4:] - nominal[4:]).max() > 1e-3 and np.allclose(moved[:4], nominal[:4])


def test_insertion_cells_equal_the_simulation_json(page, report_dir):
    """Section 8 (issue: 'and, once it exists, the insertion simulation'): the summary table shows the values of
    insertion/simulation.json, the run with the limiter at its top level and the one without under 'comparison'."""
    js = json.loads((report_dir / "insertion" / "simulation.json").read_text())
    keys = ("peak_contact_force_n", "overshoot_n", "steady_insertion_force_n", "steady_insertion_depth_m",
            "positioning_error_m", "settling_time_s")
    _check_table(page, "insertion", [{"quantity": k, "with_limiter": js[k], "without_limiter": js["comparison"][k]}
                                     for k in keys])
    assert js["peak_contact_force_n"] < js["comparison"]["peak_contact_force_n"]  # the limiter limits


def test_board_cells_equal_the_cycle_json(page, report_dir):
    """Section 9 (issue 20 item 6): the shortened board's per-pin and drive sizing tables show cycle/cycle.json's
    records, every drive's RMS force beside its value with a4 = 0; the study's front shows its summary.json."""
    js = json.loads((report_dir / "cycle" / "cycle.json").read_text())
    assert js["pin_count"] == 2 and len(js["drives"]) == 4
    pin_keys = ("index", "x_m", "z_m", "first_contact_time_s", "peak_contact_force_n", "steady_insertion_force_n",
                "overshoot_n", "tool_lateral_error_at_first_contact_m", "settling_time_s", "passed")
    _check_table(page, "cycle-pins", [{k: p[k] for k in pin_keys} for p in js["pins"]])
    drive_keys = ("leg", "peak_force_n", "rms_force_n", "rms_force_without_preload_n", "peak_speed_m_per_s",
                  "peak_power_w", "positive_energy_j", "regenerative_energy_j")
    _check_table(page, "cycle-drives", [{k: d[k] for k in drive_keys} for d in js["drives"]])
    _check_table(page, "cycle-front", STUDY_FRONT)
    md = (report_dir / "report.md").read_text()
    assert "## 8. The shipped board's work cycle" in md and "first 2 pins" in md


def test_compare_cells_equal_the_compare_json(page, report_dir):
    """Section 10 (issue 21 item 4): the machines-compared table shows compare/compare.json's records (the
    report's machine first, then the shipped 3-UPU, gantry and turned 4-UPU), and every claim is stated."""
    js = json.loads((report_dir / "compare" / "compare.json").read_text())
    keys = ("name", "legs", "worst_drive_force_n", "worst_bending_nm", "weakest_stiffness_worst_n_per_m",
            "vertical_stiffness_worst_n_per_m", "tilt_worst_rad", "first_frequency_lowest_hz", "moving_mass_kg",
            "lost_motion_m", "lost_motion_preloaded_m", "critical_preload_worst_n")
    assert [m["name"] for m in js["machines"]] == ["pressfit-4upu", "tsai-3upu", "gantry-cartesian",
                                                   "pressfit-4upu-rotated45"]
    _check_table(page, "compare-machines", [{k: m[k] for k in keys} for m in js["machines"]])
    md = (report_dir / "report.md").read_text()
    assert "## 9. The machines compared" in md and all(c["claim"] in md for c in js["claims"])
    assert all(c["verdict"] in ("confirmed", "refuted") or c["verdict"].startswith("holds on ")
               for c in js["claims"])  # all three measured


def test_report_quick_writes_every_section(report_dir):
    """`pressfit report --quick`'s report.md: every section, every figure it links exists."""
    tmp_path = report_dir
    text = (tmp_path / "report.md").read_text()
    for n in range(1, 8):  # tables, kinematics, envelope, stiffness, preload, interference, insertion
        assert f"## {n}." in text
    for link in [line.split("](")[1][:-1] for line in text.splitlines() if line.startswith("![")]:
        assert (tmp_path / link).exists(), link


_FIGURE_AFTER = """id => { let e = document.getElementById(id);
  while (e && !(e.classList && e.classList.contains('plot'))) e = e.nextElementSibling;
  return [e._fullData.map(t => ({name: t.name, x: Array.from(t.x || []), y: Array.from(t.y || [])})),
          [e._fullLayout.xaxis.title.text, e._fullLayout.xaxis2.title.text, e._fullLayout.yaxis.title.text]]; }"""


def _csv(path):
    rows = path.read_text().splitlines()
    return rows[0].split(","), np.array([[float(v) if v else np.nan for v in r.split(",")] for r in rows[1:]])


def test_joint_cells_and_figure_equal_the_joint_files(page, report_dir):
    """Section 11 (issue 30 item 7): the joint tables show joint/joint.json's records; the figure's nominal curves
    are joint/curve.csv's force against its true and sensed depth (mm), its band joint/band.csv's outer quantiles,
    and one trace per board pin its force against its sensed minus true depth (um) from joint/board_curves.csv; the
    axes say so; report.md states the band's sample count (--quick: 100) and shows the figure."""
    from pressfit.output.curve_files import BOARD_PIN_COLUMNS, JOINT_CURVE_KEYS

    js = json.loads((report_dir / "joint" / "joint.json").read_text())
    _check_table(page, "joint-curve", [{"quantity": k, "value": js["curve"][k]} for k in JOINT_CURVE_KEYS])
    _check_table(page, "joint-board", [{k: p[k] for k in BOARD_PIN_COLUMNS} for p in js["board_pins"]])
    traces, (x1, x2, y1) = page.evaluate(_FIGURE_AFTER, "joint")
    by_name = {t["name"]: t for t in traces}
    head, curve = _csv(report_dir / "joint" / "curve.csv")
    depth, sensed, force = (curve[:, head.index(k)] for k in ("depth_m", "sensed_depth_m", "force_n"))
    np.testing.assert_allclose(by_name["nominal, true depth"]["x"], depth * 1e3, rtol=1e-12)
    np.testing.assert_allclose(by_name["nominal, sensed depth"]["x"], sensed * 1e3, rtol=1e-12)
    np.testing.assert_allclose(by_name["nominal, sensed depth"]["y"], force, rtol=1e-12)
    head, band = _csv(report_dir / "joint" / "band.csv")
    band_trace = next(t for n, t in by_name.items() if n and n.startswith("band q"))
    upper = np.array(band_trace["y"], dtype=float)  # the upper quantile, filled down to the lower
    np.testing.assert_allclose(upper, band[:, -1], rtol=1e-12)
    head, board = _csv(report_dir / "joint" / "board_curves.csv")
    pins = [t for n, t in by_name.items() if n and n.startswith("pin ")]
    assert len(pins) == len(js["board_pins"]) == 20
    for t, p in zip(pins, js["board_pins"], strict=True):
        rows = board[board[:, 0] == p["index"]]
        np.testing.assert_allclose(t["x"], (rows[:, 2] - rows[:, 1]) * 1e6, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(t["y"], rows[:, 3], rtol=1e-12)
    assert "depth [mm]" in x1 and "sensed minus true depth [um]" in x2 and y1 == "force [N]"
    md = (report_dir / "report.md").read_text()
    assert "## 10. The joint and its press curve" in md and "100 samples" in md and "(joint/joint.png)" in md

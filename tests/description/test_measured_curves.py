"""Reading measured curves and windows.json: units from the header (kN, mm, ms) against the values written,
decimal comma, the part protocol's header block, the return stroke, and every refusal naming file, row and
column."""

import json

import numpy as np
import pytest

from pressfit.description import measured_curves as mc
from pressfit.description.measured_curves import read_curve
from pressfit.description.monitor_windows import load_windows
from pressfit.errors import CurveFileError, ModelFileError


def _write(tmp_path, text, name="c.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_units_from_the_header_kn_mm_ms(tmp_path):
    c = read_curve(_write(tmp_path, "Time [ms],Displacement [mm],Force [kN]\n0,0.0,0.0\n10,0.5,0.12\n20,1.0,0.4\n"))
    np.testing.assert_allclose(c.displacement_m, [0.0, 0.5e-3, 1e-3], rtol=1e-15)
    np.testing.assert_allclose(c.force_n, [0.0, 120.0, 400.0], rtol=1e-15)
    np.testing.assert_allclose(c.time_s, [0.0, 0.01, 0.02], rtol=1e-15)
    assert c.layout == "csv" and c.name == "c" and list(c.lines) == [2, 3, 4]


def test_semicolons_decimal_comma_suffix_and_parenthesis_units(tmp_path):
    c = read_curve(_write(tmp_path, "Weg (mm);kraft_n\n0,25;1,5\n0,5;2\n"))
    np.testing.assert_allclose(c.displacement_m, [0.25e-3, 0.5e-3])
    np.testing.assert_allclose(c.force_n, [1.5, 2.0])
    assert c.time_s is None


def test_units_from_the_caller_when_the_header_names_none(tmp_path):
    p = _write(tmp_path, "x,y\n0,0\n1,2\n")
    c = read_curve(p, units={"displacement": "mm", "force": "kN"})
    np.testing.assert_allclose(c.force_n, [0.0, 2000.0])
    with pytest.raises(CurveFileError) as e:
        read_curve(p)
    assert (e.value.row, e.value.column) == (1, "x") and "no unit" in str(e.value)


def test_part_protocol_header_block_and_unit_row(tmp_path):
    text = "Part number;A-7\nDate;2026-12-06\nProgram;3;pin\n\nZeit;Weg;Kraft\ns;mm;kN\n0;0;0\n0,1;1,5;0,2\n"
    c = read_curve(_write(tmp_path, text))
    assert c.layout == "part_protocol" and c.name == "A-7" and c.header["Date"] == "2026-12-06"
    np.testing.assert_allclose(c.displacement_m, [0.0, 1.5e-3])
    np.testing.assert_allclose(c.force_n, [0.0, 200.0])
    assert list(c.lines) == [7, 8]


def test_a_return_stroke_after_the_maximum_is_kept_and_cut_for_judging(tmp_path):
    c = read_curve(_write(tmp_path, "x_mm,force_n\n0,0\n1,10\n2,50\n1.5,20\n0.5,0\n"))
    assert c.forward_end == 2
    x, f = c.forward()
    np.testing.assert_allclose(x, [0.0, 1e-3, 2e-3])
    np.testing.assert_allclose(f, [0.0, 10.0, 50.0])


@pytest.mark.parametrize(("text", "row", "column", "words"), [
    ("x_mm,force_n\n0,0\n1,nan\n", 3, "force_n", "not a finite number"),
    ("x_mm,force_n\n0,0\n1,abc\n", 3, "force_n", "not a number"),
    ("x_mm,force_n\n0,0\n1,\n", 3, "force_n", "no value"),
    ("x_mm,force_n\n", 1, "x_mm", "empty curve"),
    ("x_mm,force_n\n0,0\n", 2, "x_mm", "one-point curve"),
    ("x_mm,force_n\n0,0\n1,1\n0.9,1\n2,5\n", 4, "x_mm", "runs backwards"),
    ("Displacement [in],Force [N]\n0,0\n1,1\n", 1, "Displacement [in]", "unknown displacement unit"),
    ("Displacement [mm],Force [lbf]\n0,0\n1,1\n", 1, "Force [lbf]", "unknown force unit"),
    ("t_s,x_mm,force_n\n0,0,0\n-1,1,1\n", 3, "t_s", "time runs backwards"),
    ("a,b\n0,0\n", 1, None, "no header row"),
    ("depth_m,depth_mm,force_n\n0,0,0\n", 1, "depth_mm", "two displacement columns"),
])
def test_bad_input_names_file_row_and_column(tmp_path, text, row, column, words):
    p = _write(tmp_path, text)
    with pytest.raises(CurveFileError) as e:
        read_curve(p)
    assert (e.value.path, e.value.row, e.value.column) == (str(p), row, column)
    assert words in str(e.value) and str(p) in str(e.value)


def test_a_backwards_step_within_the_tolerance_is_jitter(tmp_path):
    """1 um allowed before the maximum: 0.5 um back reads, 2 um back is refused."""
    assert read_curve(_write(tmp_path, "x_mm,force_n\n0,0\n1,1\n0.9995,1\n2,5\n")).forward_end == 3
    with pytest.raises(CurveFileError):
        read_curve(_write(tmp_path, "x_mm,force_n\n0,0\n1,1\n0.998,1\n2,5\n"))


def test_a_file_of_10_mb_is_refused_before_reading(tmp_path, monkeypatch):
    p = _write(tmp_path, "x_mm,force_n\n0,0\n1,1\n")
    with open(p, "ab") as fh:
        fh.truncate(mc.MAX_CURVE_BYTES)
    monkeypatch.setattr(type(p), "read_bytes", lambda self: pytest.fail("read"))
    with pytest.raises(CurveFileError) as e:
        read_curve(p)
    assert e.value.row is None and "10000000 bytes" in str(e.value)
    with open(p, "ab") as fh:
        fh.truncate(mc.MAX_CURVE_BYTES - 1)
    monkeypatch.undo()
    with pytest.raises(CurveFileError) as e:  # just under the limit: read (and refused for its NUL bytes)
        read_curve(p)
    assert "bytes: a curve file" not in str(e.value)


def _windows(tmp_path, data):
    p = tmp_path / "w.json"
    p.write_text(json.dumps(data))
    return p


WINDOW = {"type": "window", "name": "w", "x_min_m": 0.001, "x_max_m": 0.002, "y_min_n": 10.0, "y_max_n": 20.0,
          "entry": "left", "exit": "right"}


def test_windows_file_reads_and_refuses_with_the_key(tmp_path):
    w = load_windows(_windows(tmp_path, {"schema_version": 1, "elements": [WINDOW, {"type": "max_force",
                                                                                     "name": "m", "force_n": 5}]}))
    assert [e.type for e in w.elements] == ["window", "max_force"]
    bad = [({"schema_version": 2, "elements": [WINDOW]}, "schema_version"),
           ({"schema_version": 1, "elements": [{**WINDOW, "x_max_m": 0.0005}]}, "elements.0"),
           ({"schema_version": 1, "elements": [{**WINDOW, "entry": "front"}]}, "entry"),
           ({"schema_version": 1, "elements": [WINDOW, WINDOW]}, "<top level>"),
           ({"schema_version": 1, "elements": [{**WINDOW, "x_min_mm": 1}]}, "x_min_mm"),
           ({"schema_version": 1, "elements": [{"type": "envelope", "name": "e", "displacement_m": [0, 1],
                                                  "lower_force_n": [0, 2], "upper_force_n": [1, 1]}]}, "elements.0")]
    for data, key in bad:
        with pytest.raises(ModelFileError) as e:
            load_windows(_windows(tmp_path, data))
        assert key in e.value.key, (data, e.value)

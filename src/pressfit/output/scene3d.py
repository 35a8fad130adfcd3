"""The 3D view of ``report.html``: the loaded machine as a plotly figure (mesh3d tubes and boxes).

The bodies are the interference model's own shapes (:func:`pressfit.geometry.interference.machine_shapes`:
radii, lengths, boxes and their placements on the cylinder, stem, plate and world frames); capsules are
drawn as open tubes of the same radius and length (without their end caps). The numbers are those of
one :func:`pressfit.mechanics.statics.solve_equilibrium` per case; nothing is recomputed here.

Deflected shape, magnified by m (a slider; m = 0 is the nominal pose): plate centre h + m u, plate
rotation exp(m phi) (u, phi: the plate displacement and rotation vector of the solve), plate cardans
C_i = h + m u + exp(m phi) d_i, and each leg straight from its base cardan B_i to C_i, its frame from
:func:`pressfit.kinematics.closed_form.frames_along` (e_x = the base cardan axis made normal to the leg).

Colouring (a toggle): the axial force N (N, > 0 tension) and the torsion T (N m) are constant along a
leg (no loads act between its cardans), drawn on a diverging scale symmetric about 0; the bending
magnitude |M| = hypot(M_x, M_y) (N m) varies linearly along each segment with the shear, so each tube
vertex gets M_x and M_y interpolated between the solver's base, actuator (cylinder end) and plate sections.
One colour scale serves every case, so cases compare by colour.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
import plotly.graph_objects as go
from plotly.colors import get_colorscale

from pressfit.geometry.interference import machine_shapes
from pressfit.kinematics.closed_form import frames_along

if TYPE_CHECKING:
    from pressfit.description.machine import Machine
    from pressfit.geometry.interference import Shape
    from pressfit.mechanics.statics import Equilibrium

MAGNIFICATIONS = (0.0, 1.0, 10.0, 30.0, 100.0, 300.0, 1000.0, 3000.0)
VISIBLE_DEFLECTION_M = 0.05  # the default magnification is the largest that keeps every cardan within this
# key -> (button label, colour-bar title, colour scale (sent as a list: plotly.js lacks most names), symmetric)
COLOURINGS = {
    "axial": ("axial force", "N [N]<br>(> 0 tension)", "RdBu_r", True),
    "torsion": ("torsion", "T [N m]", "PuOr", True),
    "bending": ("bending", "|M| [N m]", "Viridis", False),
}
_TUBE_SIDES = 18
_BODY_COLOURS = {"plate": "#8c96a8", "base": "#c8ccd2"}


@dataclass(frozen=True)
class SceneCase:
    """One selectable state of the 3D view: a label and its equilibrium (with its machine)."""

    label: str
    equilibrium: Equilibrium


def _tube(radius_m: float, half_length_m: float, placement: pin.SE3) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (2k, 3) and triangles (2k, 3) of an open tube along the placement's z axis, centred on it."""
    a = np.linspace(0.0, 2 * np.pi, _TUBE_SIDES, endpoint=False)
    ring = np.stack([radius_m * np.cos(a), radius_m * np.sin(a)], -1)
    local = np.concatenate([np.c_[ring, np.full(_TUBE_SIDES, z)] for z in (-half_length_m, half_length_m)])
    k = np.arange(_TUBE_SIDES)
    nxt = (k + 1) % _TUBE_SIDES
    faces = np.concatenate([np.c_[k, nxt, k + _TUBE_SIDES], np.c_[nxt, nxt + _TUBE_SIDES, k + _TUBE_SIDES]])
    return local @ placement.rotation.T + placement.translation, faces


def _box(half_sides_m: np.ndarray, placement: pin.SE3) -> tuple[np.ndarray, np.ndarray]:
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half_sides_m
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return corners @ placement.rotation.T + placement.translation, faces


def _geometry(shape: Shape, placement: pin.SE3) -> tuple[np.ndarray, np.ndarray | None]:
    """World vertices and triangles of a shape (None: a convex hull, triangulated by plotly)."""
    g = shape.geometry
    if hasattr(g, "halfSide"):
        return _box(np.asarray(g.halfSide), placement)
    if hasattr(g, "halfLength"):
        return _tube(g.radius, g.halfLength, placement)
    return np.asarray(g.points()) @ placement.rotation.T + placement.translation, None


def _carriers(machine: Machine, eq: Equilibrium, magnification: float) -> tuple[dict, np.ndarray]:
    """World placements of the shape carriers in the deflected state magnified by ``magnification``,
    and the plate cardan centres C_i (n, 3), m."""
    centre = eq.pose_m + magnification * eq.plate_displacement_m
    rot = pin.exp3(magnification * eq.plate_rotation_rad)
    cardans = centre + machine.plate_offsets_m @ rot.T
    legs = cardans - machine.base_points_m
    frames = frames_along(machine, legs / np.linalg.norm(legs, axis=1, keepdims=True))
    out = {("world", -1): pin.SE3.Identity(), ("plate", -1): pin.SE3(rot, centre)}
    for i in range(len(machine.legs)):
        out[("cylinder", i)] = pin.SE3(frames[i], machine.base_points_m[i])
        out[("stem", i)] = pin.SE3(frames[i], cardans[i])
    return out, cardans


def _leg_colours(machine: Machine, eq: Equilibrium, leg: int, vertices: np.ndarray, length_m: float,
                 frame: np.ndarray) -> dict[str, np.ndarray]:
    """Per-vertex colour values of a leg shape (module doc): N, T constant; |M| interpolated along the leg."""
    sec = eq.legs[leg].sections
    s = (vertices - machine.base_points_m[leg]) @ frame[:, 2]
    at = [0.0, machine.cylinder.length_m, length_m]
    mx, my = (np.interp(s, at, [getattr(sec[k], c) for k in ("base", "actuator", "plate")]) for c in ("M_x", "M_y"))
    n = np.ones(len(vertices))
    return {"axial": n * sec["actuator"].N, "torsion": n * sec["actuator"].T, "bending": np.hypot(mx, my)}


def _leg_hover(eq: Equilibrium, leg: int, part: str, label: str) -> str:
    sec = eq.legs[leg].sections
    bend = ", ".join(f"{k} {np.hypot(sec[k].M_x, sec[k].M_y):.3g}" for k in ("base", "actuator", "plate"))
    return (f"<b>leg {leg + 1} {part}</b><br>N = {sec['actuator'].N:.1f} N (> 0 tension)<br>"
            f"T = {sec['actuator'].T:.3g} N m<br>|M| [N m]: {bend}<br>actuator force = "
            f"{eq.legs[leg].actuator_force_n:.1f} N<extra>{label}</extra>")


def _positions(machine: Machine, eq: Equilibrium, shapes: list[Shape], magnification: float) -> list[np.ndarray]:
    """World vertices (n, 3) of every shape, then the 2n cardans (B_1..n, C_1..n), at a magnification."""
    carriers, cardans = _carriers(machine, eq, magnification)
    return ([_geometry(s, carriers[s.carrier] * s.local)[0] for s in shapes]
            + [np.vstack([machine.base_points_m, cardans])])


def _default_magnification(machine: Machine, cases: list[SceneCase]) -> float:
    """The largest of MAGNIFICATIONS that keeps every plate cardan within VISIBLE_DEFLECTION_M of its place."""
    def moved(eq: Equilibrium, m: float) -> float:
        return float(np.abs(_carriers(machine, eq, m)[1] - _carriers(machine, eq, 0.0)[1]).max())
    return max(m for m in MAGNIFICATIONS if all(moved(c.equilibrium, m) <= VISIBLE_DEFLECTION_M for c in cases))


def _xyz(vertices: np.ndarray) -> dict[str, list[float]]:
    return {a: np.round(vertices[:, j], 7).tolist() for j, a in enumerate("xyz")}  # 0.1 um


def _case_traces(machine: Machine, case: SceneCase, shapes: list[Shape], magnification: float,
                 visible: bool) -> tuple[list[dict], dict[int, dict[str, np.ndarray]]]:
    """One case's traces (plotly dicts) at a magnification, and the colour values of its leg traces by index."""
    eq = case.equilibrium
    at_one = _positions(machine, eq, shapes, 1.0)
    carriers_one, cardans_one = _carriers(machine, eq, 1.0)
    shown = _positions(machine, eq, shapes, magnification)
    traces, colours = [], {}
    for t, shape in enumerate(shapes):
        faces = _geometry(shape, pin.SE3.Identity())[1]
        tr = {"type": "mesh3d", "name": shape.name, "visible": visible, **_xyz(shown[t]),
              **({"alphahull": 0} if faces is None else {"i": faces[:, 0].tolist(), "j": faces[:, 1].tolist(),
                                                         "k": faces[:, 2].tolist()})}
        kind, leg = shape.carrier
        if leg >= 0:
            length = float(np.linalg.norm(cardans_one[leg] - machine.base_points_m[leg]))
            colours[t] = _leg_colours(machine, eq, leg, at_one[t], length, carriers_one[("cylinder", leg)].rotation)
            tr.update(coloraxis="coloraxis", intensity=colours[t]["axial"].tolist(),
                      hovertemplate=_leg_hover(eq, leg, shape.name.split(".", 1)[1], case.label))
        else:
            tr.update(color=_BODY_COLOURS.get(shape.body, "#d9a441"), opacity=0.6 if shape.body == "base" else 1.0,
                      hovertemplate=f"<b>{shape.name}</b><br>plate displacement (x, y, z) "
                                    f"{np.round(eq.plate_displacement_m * 1e6, 2).tolist()} um<br>plate rotation "
                                    f"{np.round(eq.plate_rotation_rad * 1e3, 4).tolist()} mrad"
                                    f"<extra>{case.label}</extra>")
        traces.append(tr)
    traces.append({"type": "scatter3d", "mode": "markers", "name": "cardans", "visible": visible, **_xyz(shown[-1]),
                   "marker": {"size": 4, "color": "black", "symbol": "diamond"},
                   "text": [f"{kind} cardan {c}_{i + 1}" for kind, c in (("base", "B"), ("plate", "C"))
                            for i in range(len(machine.legs))],
                   "hovertemplate": "%{text}<br>(%{x:.4f}, %{y:.4f}, %{z:.4f}) m<extra>" + case.label + "</extra>"})
    return traces, colours


def _colour_axis(colours: list[dict[str, np.ndarray]], key: str) -> dict[str, object]:
    """Layout keys of the shared colour axis for one colouring (module doc)."""
    _, title, scale, symmetric = COLOURINGS[key]
    top = max(float(np.abs(c[key]).max()) for c in colours) or 1.0
    return {"coloraxis.colorscale": get_colorscale(scale), "coloraxis.cmin": -top if symmetric else 0.0,
            "coloraxis.cmax": top, "coloraxis.colorbar.title.text": title}


def scene_figure(machine: Machine, cases: list[SceneCase]) -> go.Figure:
    """The 3D view (module doc): a case dropdown, a colouring toggle and a magnification slider."""
    shapes, _ = machine_shapes(machine)
    mag = _default_magnification(machine, cases)
    traces, colours, owner = [], {}, []
    for c, case in enumerate(cases):
        tr, col = _case_traces(machine, case, shapes, mag, visible=c == 0)
        colours.update({len(traces) + t: v for t, v in col.items()})
        owner += [c] * len(tr)
        traces += tr
    legs = sorted(colours)
    colour_buttons = [{"label": label, "method": "update",
                       "args": [{"intensity": [colours[t][key].tolist() for t in legs]},
                                _colour_axis(list(colours.values()), key), legs]}
                      for key, (label, *_) in COLOURINGS.items()]
    case_buttons = [{"label": case.label, "method": "update",
                     "args": [{"visible": [o == c for o in owner]}, {"title.text": _title(case, mag)}]}
                    for c, case in enumerate(cases)]
    steps = []
    for m in MAGNIFICATIONS:
        pos = [p for case in cases for p in _positions(machine, case.equilibrium, shapes, m)]
        xyz = [_xyz(p) for p in pos]
        steps.append({"label": f"{m:g}", "method": "restyle",
                      "args": [{a: [v[a] for v in xyz] for a in "xyz"}, list(range(len(traces)))]})
    axis = {"showbackground": False}
    fig = go.Figure(data=traces)
    fig.update_layout(
        title={"text": _title(cases[0], mag), "y": 0.98}, height=760, margin={"l": 0, "r": 0, "t": 110, "b": 0},
        showlegend=False,
        scene={"aspectmode": "data", "camera": {"up": {"x": 0, "y": 1, "z": 0}, "eye": {"x": 1.5, "y": 0.9, "z": 1.6}},
               "xaxis": {**axis, "title": {"text": "x [m]"}}, "yaxis": {**axis, "title": {"text": "y [m] (up)"}},
               "zaxis": {**axis, "title": {"text": "z [m]"}}},
        updatemenus=[{"type": "buttons", "direction": "right", "x": 0.0, "y": 1.02, "xanchor": "left",
                      "yanchor": "bottom", "buttons": colour_buttons, "showactive": True, "active": 0},
                     {"type": "dropdown", "x": 1.0, "y": 1.02, "xanchor": "right", "yanchor": "bottom",
                      "buttons": case_buttons, "active": 0}],
        sliders=[{"active": MAGNIFICATIONS.index(mag), "steps": steps, "y": 0.02,
                  "currentvalue": {"prefix": "deflection magnification x"}}])
    fig.update_layout({k.replace(".", "_"): v for k, v in _colour_axis(list(colours.values()), "axial").items()})
    return fig


def _title(case: SceneCase, magnification: float) -> str:
    return f"{case.label} (deflection drawn x{magnification:g} at first; slider below)"

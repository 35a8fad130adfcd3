"""Commands about the machine in motion: ``pressfit modes``, ``pressfit simulate``, ``pressfit export-mjcf``,
``pressfit response``, ``pressfit control``, ``pressfit cycle``."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from pressfit.cli.common import (
    COORDINATE,
    FORCE,
    MODEL_OPTION,
    OVERWRITE_OPTION,
    FiniteFloat,
    echo_written,
    user_errors,
)
from pressfit.description.machine import load_machine
from pressfit.dynamics.machine.registry import model_names
from pressfit.dynamics.response import MAX_SAMPLES as MAX_RESPONSE_SAMPLES
from pressfit.dynamics.response import SAMPLES_PER_PERIOD
from pressfit.output.files import to_json

# s: the 60th mode at pose A is 4.4 kHz (pressfit modes --count 60), a period of 230 us that 1 us resolves
# 200 times over; a smaller step only multiplies the steps (a simulated second would take more than a million)
MIN_MJCF_TIMESTEP_S = 1e-6


@click.command("modes", context_settings={"ignore_unknown_options": True})  # negative coordinates
@click.argument("x", type=COORDINATE)
@click.argument("y", type=COORDINATE)
@click.argument("z", type=COORDINATE)
@click.option("--count", type=click.IntRange(1, 60), default=6, show_default=True, help="Number of modes.")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=None,
              help="Directory for modes.json, modes.csv and modes.png (nothing written without it).")
@OVERWRITE_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@MODEL_OPTION
@user_errors
def modes_cmd(x: float, y: float, z: float, count: int, out_dir: Path | None, overwrite: bool, as_json: bool,
              model_path: Path) -> None:
    """Natural frequencies and mode shapes at the plate pose X Y Z (m), under the plate's and tool's weight."""
    from pressfit.workflows.natural_modes import run_modes

    machine = load_machine(model_path)
    modes, paths = run_modes(machine, [x, y, z], count, out_dir, overwrite)
    if as_json:
        click.echo(to_json(modes.to_dict()))
        return
    click.echo(f"{machine.name}, {len(machine.legs)} legs: pose h = ({x:g}, {y:g}, {z:g}) m, moving mass "
               f"{modes.total_mass_kg:.4g} kg; "
               f"closure residual of the shapes {modes.closure_residual:.1e}")
    click.echo("mode  f [Hz]      plate translation [m]           plate rotation [rad]  (mass-normalised, kg^-1/2)")
    for k, (f, u) in enumerate(zip(modes.frequencies_hz, modes.plate_shapes, strict=True)):
        click.echo(f"{k + 1:>4}  {f:<10.4g}  " + " ".join(f"{c:+.3e}" for c in u[:3]) + "  "
                   + " ".join(f"{c:+.3e}" for c in u[3:]))
    echo_written(paths)


@click.command("simulate")
@click.argument("case_path", type=click.Path(path_type=Path))
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=None,
              help="Directory for simulation.csv, simulation.json and simulation.png (nothing written without it).")
@click.option("--no-limiter", "no_limiter", is_flag=True, help="Run without the insertion force limiter.")
@OVERWRITE_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar over simulated time.")
@user_errors
def simulate_cmd(case_path: Path, out_dir: Path | None, no_limiter: bool, overwrite: bool, as_json: bool,
                 progress: bool) -> None:
    """Simulate the insertion scenario of a case file's [simulation] table (Figures 13-14), SI units."""
    from pressfit.workflows.insertion_simulation import run_simulation

    summary, paths = run_simulation(case_path, out_dir, not no_limiter, overwrite, progress)
    s = summary
    for warning in run_warnings(s):
        click.echo(f"warning: {warning}", err=True)
    if as_json:
        click.echo(to_json(summary))
        return
    click.echo(f"{s['case']}: {s['simulated_time_s']:g} s simulated, limiter "
               f"{'on' if s['limiter'] else 'off'} ({s['force_limit_n']:g} N)")
    click.echo(f"peak contact force {s['peak_contact_force_n']:.2f} N at t = {s['peak_contact_force_time_s']:.3f} s "
               f"(overshoot {s['overshoot_n']:.2f} N), steady {s['steady_insertion_force_n']:.2f} N at "
               f"{s['steady_insertion_depth_m'] * 1e3:.3f} mm; insertion "
               + ("completed" if s["insertion_completed"] else f"NOT completed ({s['insertion_note']})"))
    click.echo(f"tool error: lateral at insertion {s['tool_lateral_error_at_insertion_m'] * 1e6:.1f} um, "
               f"final {s['tool_final_error_m'] * 1e6:.1f} um; closure drift {s['max_closure_drift_m']:.1e} m "
               f"(tolerance {s['closure_drift_tolerance_m']:g} m); actuator saturation "
               f"{s['actuator_saturation_time_s']:g} s ({100 * s['actuator_saturation_fraction']:.3g}% of the run)")
    settle, release = s["settling_time_s"], s["release_time_s"]
    click.echo(f"settling (contact force within {100 * s['settling_band']:g}% of steady): "
               + ("did not settle" if settle is None else f"{settle:.3f} s")
               + "; release after the dwell " + ("never" if release is None else f"{release:.3f} s")
               + f", tool error at the end of the retract {s['retract_tool_error_m'] * 1e6:.1f} um")
    commanded = ", ".join(f"{a:g}" for a in s["commanded_preload_amplitudes_n"]) or "none: no preload space"
    click.echo(f"internal force along the preload basis {s['internal_force_range_n'][0]:.1f} .. "
               f"{s['internal_force_range_n'][1]:.1f} N (commanded {commanded} N); peak leg axial force "
               + " ".join(f"{x:.1f}" for x in s["peak_leg_axial_force_n"]) + " N")
    click.echo(f"model {s['model']}: tool lateral error at first contact "
               + ("(no contact)" if s["tool_lateral_error_at_first_contact_m"] is None else
                  f"{s['tool_lateral_error_at_first_contact_m'] * 1e6:.1f} um")
               + f", max over the dwell {s['tool_lateral_error_dwell_max_m'] * 1e6:.1f} um; structure deflection "
               "during the moves (tool - kinematic pose) "
               + ("n/a" if s["max_move_deflection_m"] is None else f"{s['max_move_deflection_m'] * 1e6:.2f} um")
               + "; residual vibration at the end pose "
               + ("n/a (no settle)" if s["residual_vibration_m"] is None else
                  f"{s['residual_vibration_m'] * 1e6:.2f} um peak-to-peak over {s['residual_vibration_window_s']:g} s"))
    click.echo("drives: peak tension " + " ".join(f"{x:.1f}" for x in s["peak_actuator_tension_n"]) + " N, RMS "
               + " ".join(f"{x:.1f}" for x in s["rms_actuator_tension_n"]) + " N, peak speed "
               + " ".join(f"{x * 1e3:.1f}" for x in s["peak_actuator_speed_m_per_s"]) + " mm/s")
    if "drives" in s:
        _echo_sizing(s)
    if "peak_leg_torsion_nm" in s:
        click.echo("leg sections (elastic model, base/actuator/plate): peak torsion "
                   + " ".join(f"{x:.2f}" for x in s["peak_leg_torsion_nm"]) + " N m, peak bending "
                   + " ".join(f"{x:.2f}" for x in s["peak_leg_bending_nm"]) + " N m")
    if "comparison" in s:
        c = s["comparison"]
        click.echo(f"without the limiter: peak {c['peak_contact_force_n']:.2f} N, steady "
                   f"{c['steady_insertion_force_n']:.2f} N")
    echo_written(paths)


def run_warnings(summary: dict) -> list[str]:
    """The warnings of a simulation summary: the run's, then those of its comparison run (the other limiter
    setting) that the run does not give, each saying it is about the comparison run."""
    own = list(dict.fromkeys(summary["warnings"]))
    comparison = summary.get("comparison")
    if not comparison:
        return own
    label = f"the comparison run (limiter {'on' if comparison['limiter'] else 'off'}, not the main run)"
    return own + [f"{label}: {w}" for w in dict.fromkeys(comparison["warnings"]) if w not in own]


def _each(drives: list[dict], key: str, fmt: str) -> str:
    return " ".join(f"{d[key]:{fmt}}" for d in drives)


def _echo_sizing(s: dict) -> None:
    """The drive sizing's lines of ``pressfit simulate`` (per leg 1..4; a figure over its rating is marked)."""
    drives = s["drives"]

    def row(key: str, scale: float = 1.0, fmt: str = ".1f") -> str:
        out = []
        for d in drives:
            rating = d["ratings"].get(key)
            mark = "" if rating is None else f" ({100 * rating['ratio']:.0f}%{' OVER' * rating['exceeded']})"
            out.append(f"{d[key] * scale:{fmt}}{mark}")
        return " ".join(out)

    rated = sorted({k for d in drives for k in d["ratings"]})
    click.echo(f"drive sizing (legs 1-{len(drives)}; % of the rating: {', '.join(rated)}): peak force "
               f"{row('peak_force_n')} N, RMS force {row('rms_force_n')} N"
               + (f" ({_each(drives, 'rms_force_without_preload_n', '.1f')} N with a4 = 0)"
                  if "rms_force_without_preload_n" in drives[0] else "")
               + f", peak speed {row('peak_speed_m_per_s', 1e3)} mm/s, peak power {row('peak_power_w')} W, energy "
               + " ".join(f"+{d['positive_energy_j']:.2f}/-{d['regenerative_energy_j']:.2f}" for d in drives) + " J")
    if "rms_torque_nm" in drives[0]:
        loss = drives[0]["copper_loss_w"] is not None
        click.echo(f"motors: RMS torque {row('rms_torque_nm', 1.0, '.3f')} N m, RMS current "
                   f"{row('rms_current_a', 1.0, '.3f')} A, peak speed "
                   f"{row('peak_motor_speed_rad_per_s', 1.0, '.0f')} rad/s"
                   + (f", copper loss {row('copper_loss_w', 1.0, '.2f')} W" if loss else "")
                   + (f" ({_each(drives, 'copper_loss_without_preload_w', '.2f')} W with a4 = 0)"
                      if loss and "copper_loss_without_preload_w" in drives[0] else ""))
    if "periodic_winding_rise_k" in drives[0]:
        click.echo(f"linear motors: RMS current {row('rms_current_a', 1.0, '.3f')} A, copper loss "
                   f"{row('copper_loss_w', 1.0, '.2f')} W, winding rise {row('peak_winding_rise_k', 1.0, '.3f')} K "
                   f"(cold start), {row('periodic_winding_rise_k', 1.0, '.2f')} K (the motion repeated, periodic)")
    if "peak_flow_m3_per_s" in drives[0]:
        click.echo(f"valves: peak flow {row('peak_flow_m3_per_s', 6e4, '.2f')} l/min, supplied power p_s Q peak "
                   f"{row('peak_supply_power_w')} W, mean {row('mean_supply_power_w')} W")
    e = s["energy_balance"]
    click.echo(f"energy balance: drive work {e['drive_work_j']:.4g} J = kinetic {e['kinetic_change_j']:.4g} + "
               f"potential {e['potential_change_j']:.4g} + elastic {e['elastic_change_j']:.4g} + pin "
               f"{e['pin_work_j']:.4g} + damping {e['damping_j']:.4g}"
               + (f" + plays' stored {e['play_energy_change_j']:.3g} + plays' dissipation {e['play_dissipation_j']:.4g}"
                  if e.get("play_energy_change_j") or e.get("play_dissipation_j") else "")
               + (f" + series springs' loss {e['series_loss_j']:.3g}" if e.get("series_loss_j") else "")
               + f" + residual {e['residual_j']:.3g} J "
               f"({100 * e['relative_residual']:.2g}% of the drives' gross work {e['gross_drive_work_j']:.4g} J, "
               f"tolerance {100 * e['tolerance']:g}%); drive losses {e['drive_losses_j']:.4g} J")


@click.command("export-mjcf", context_settings={"ignore_unknown_options": True})  # negative coordinates
@click.argument("x", type=COORDINATE)
@click.argument("y", type=COORDINATE)
@click.argument("z", type=COORDINATE)
@click.option("--timestep", "timestep_s", type=FiniteFloat(MIN_MJCF_TIMESTEP_S, 0.01), default=1e-4,
              show_default=True, help="MuJoCo time step (s), in [1e-6, 0.01]; the welds' time constant is twice "
              "it.")
@click.option("--out", type=click.Path(path_type=Path), default=None,
              help="MJCF file to write (printed to standard output without it).")
@click.option("--overwrite", is_flag=True, help="Replace an existing output file.")
@MODEL_OPTION
@user_errors
def export_mjcf_cmd(x: float, y: float, z: float, timestep_s: float, out: Path | None, overwrite: bool,
                    model_path: Path) -> None:
    """The rigid-leg machine closed at the plate pose X Y Z (m) as a MuJoCo model (MJCF, SI units): bodies,
    masses, gravity, the loop closures (one per leg) as welds, a keyframe 'reference' at the pose."""
    from pressfit.workflows.mjcf_export import export_mjcf

    text, path = export_mjcf(load_machine(model_path), [x, y, z], timestep_s, out, overwrite)
    click.echo(f"wrote {path}" if path is not None else text)


@click.command("response", context_settings={"ignore_unknown_options": True})  # negative coordinates
@click.argument("x", type=COORDINATE)
@click.argument("y", type=COORDINATE)
@click.argument("z", type=COORDINATE)
@click.option("--force", "force_n", type=FORCE, nargs=3, required=True,
              help="FX FY FZ: the force step at the tool (N, world axes).")
@click.option("--duration", "duration_s", type=FiniteFloat(0.0, 60.0, open_low=True), default=0.5,
              show_default=True, help="Simulated time after the step (s), in (0, 60] and at most "
              f"{MAX_RESPONSE_SAMPLES} samples at {SAMPLES_PER_PERIOD} per period of the fastest contributing mode "
              "(a few seconds, by pose and force direction: a longer one is refused before the history is computed, "
              "naming the longest).")
@click.option("--damping-ratio", type=FiniteFloat(0.0, 1.0), default=0.02, show_default=True,
              help="Modal damping ratio of every mode, in [0, 1]: 0 undamped, 1 critical (an estimate; 1-5% is "
              "typical of bolted steel frames).")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=None,
              help="Directory for response.json, response.csv, receptance.csv and response.png.")
@OVERWRITE_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@MODEL_OPTION
@user_errors
def response_cmd(x: float, y: float, z: float, force_n: tuple[float, float, float], duration_s: float,
                 damping_ratio: float, out_dir: Path | None, overwrite: bool, as_json: bool, model_path: Path) -> None:
    """Tool-point response at the plate pose X Y Z (m), drives holding their lengths: a force step at the tool
    (displacement history) and the receptance (frequency response) with its peaks at the modes. Linear, about
    the equilibrium under the weight: a step with a buckling factor below 10, a peak plate rotation beyond
    0.01 rad or a tool translation beyond 1% of the shortest leg is refused (pressfit solve answers it)."""
    from pressfit.workflows.step_response import run_response

    r, paths = run_response(load_machine(model_path), [x, y, z], list(force_n), duration_s, damping_ratio, out_dir,
                            overwrite)
    s = r.summary()
    if as_json:
        click.echo(to_json(s))
        return
    click.echo(f"pose h = ({x:g}, {y:g}, {z:g}) m, step F = ({', '.join(f'{f:g}' for f in force_n)}) N at the tool, "
               f"modal damping {damping_ratio:g}")
    click.echo(f"static: lateral {s['static_lateral_m'] * 1e6:.3f} um, "
               f"vertical {s['static_vertical_m'] * 1e6:+.3f} um; "
               f"peak: lateral {s['peak_lateral_m'] * 1e6:.3f} um, vertical {s['peak_vertical_m'] * 1e6:+.3f} um")
    click.echo(f"dominant mode {s['dominant_frequency_hz']:.4g} Hz; lowest modes "
               + ", ".join(f"{f:.4g}" for f in s["lowest_modes_hz"]) + " Hz; receptance peaks "
               + (", ".join(f"{f:.4g}" for f in s["receptance_peak_hz"]) + " Hz" if s["receptance_peak_hz"]
                  else "none"))
    echo_written(paths)


@click.command("control")
@click.argument("case_path", type=click.Path(path_type=Path))
@click.option("--model", "plant_model", type=click.Choice(model_names()), default=None,
              help="The machine linearised: elastic VJM legs or rigid legs (fast); default: the case's "
                   "[simulation] model.")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=None,
              help="Directory for control.json, poles.csv and bode.png (nothing written without it).")
@OVERWRITE_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@user_errors
def control_cmd(case_path: Path, plant_model: str | None, out_dir: Path | None, overwrite: bool, as_json: bool) -> None:
    """The case's insertion loop (machine, drives, controller) linearised at the pin and the waypoints: margins,
    closed-loop poles, -3 dB bandwidth, structural modes and the drives' share of each."""
    from pressfit.workflows.control_design import run_control

    design, paths = run_control(case_path, plant_model, out_dir, overwrite)
    if as_json:
        click.echo(to_json(design.to_dict()))
        return
    for p in design.poses:
        click.echo(f"{p.name} ({', '.join(f'{c:g}' for c in p.pose_m)}) m, {p.model}"
                   f"{', in contact' if p.in_contact else ''}: {'stable' if p.stable else 'UNSTABLE'}; -3 dB "
                   f"bandwidth vertical {p.bandwidth_vertical_hz:.3g} Hz, lateral {p.bandwidth_lateral_hz:.3g} Hz")
        for m in p.margins:
            click.echo(f"  axis {m.axis}: gain margin {m.gain_margin:.3g} at {m.phase_crossover_hz:.3g} Hz, "
                       f"phase margin {m.phase_margin_deg:.3g} deg at {m.gain_crossover_hz:.3g} Hz")
        click.echo("  loop poles [Hz (damping)]: " + ", ".join(
            f"{q['frequency_hz']:.3g} ({q['damping']:.2f})" for q in p.to_dict()["loop_poles"]))
        click.echo("  structural modes [Hz (share of strain energy in the drives)]: "
                   + ", ".join(f"{m.frequency_hz:.4g} ({m.drive_energy_fraction:.2g})" for m in p.modes))
        for w in p.warnings:
            click.echo(f"  WARNING: {w}")
    echo_written(paths)


def _echo_components(s: dict) -> None:
    """With a component of several pins (``[[cycle.contact.pins]]``): per board position the tool's largest tilt,
    the pins' largest depth spread, whether every pin seated, and each component pin's peak force."""
    if not s["pins"] or len(s["pins"][0]["component_pins"]) < 2:
        return
    click.echo(" pin  tilt [mrad]  spread [um]  seated  component pins' peak force [N]")
    for p in s["pins"]:
        peaks = " ".join(f"{c['peak_force_n']:.2f}" for c in p["component_pins"])
        click.echo(f"{p['index']:>4}  {p['tool_tilt_max_rad'] * 1e3:>11.4f}  {p['max_pin_depth_spread_m'] * 1e6:>11.3f}"
                   f"  {'yes' if p['all_pins_seated'] else 'no':>6}  {peaks}")


@click.command("cycle")
@click.argument("case_path", type=click.Path(path_type=Path))
@click.option("--model", "plant_model", type=click.Choice(model_names()), default=None,
              help="The machine simulated (default: the case's [cycle] model).")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=None,
              help="Directory for cycle.csv, cycle.json, cycle_path.png, cycle_force.png, cycle_drives.png and "
                   "cycle_operating_points.png (nothing written without it).")
@OVERWRITE_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar over simulated time.")
@user_errors
def cycle_cmd(case_path: Path, plant_model: str | None, out_dir: Path | None, overwrite: bool, as_json: bool,
              progress: bool) -> None:
    """Simulate a whole board, the case file's [cycle] table: per pin the insertion figures and pass/fail, the
    cycle time, pins per minute and what limits each segment, the drive sizing over the cycle with the preload's
    cost (a second run with a4 = 0) and the run's energy balance (SI units). Exit 1 when a pin fails its limits."""
    from pressfit.workflows.board_cycle import run_cycle

    s, paths = run_cycle(case_path, plant_model, out_dir, overwrite, progress)
    for warning in dict.fromkeys(s["warnings"]):
        click.echo(f"warning: {warning}", err=True)
    if as_json:
        click.echo(to_json(s))
    else:
        click.echo(f"{s['case']}: {s['pin_count']} pins, model {s['model']}; cycle time {s['cycle_time_s']:.3f} s, "
                   f"{s['pins_per_minute']:.2f} pins per minute; {s['pins_passed']} of {s['pin_count']} pins pass")
        slow = s["slowest_segment"]
        click.echo(f"slowest segment: {slow['phase']} of pin {slow['pin']}, {slow['duration_s']:.3f} s, limited by "
                   f"{slow['binding_limit']}")
        if "drives" in s:
            _echo_sizing(s)
        click.echo(" pin        x [m]      z [m]  contact [s]  peak [N]  steady [N]  overshoot [N]  lateral [um]  "
                   "settling [s]  result")
        for p in s["pins"]:
            lateral = p["tool_lateral_error_at_first_contact_m"]
            click.echo(f"{p['index']:>4}  {p['x_m']:>+9.4f}  {p['z_m']:>+9.4f}  "
                       + ("{:>11}".format("none" if p["first_contact_time_s"] is None else
                                          f"{p['first_contact_time_s']:.3f}"))
                       + f"  {p['peak_contact_force_n']:>8.2f}  {p['steady_insertion_force_n']:>10.2f}  "
                       f"{p['overshoot_n']:>13.2f}  " + ("{:>12}".format("n/a" if lateral is None else
                                                                         f"{lateral * 1e6:.2f}"))
                       + "  " + ("{:>12}".format("none" if p["settling_time_s"] is None else
                                                 f"{p['settling_time_s']:.3f}"))
                       + f"  {'pass' if p['passed'] else 'FAIL'}")
        _echo_components(s)
        echo_written(paths)
    if s["pins_passed"] < s["pin_count"]:
        sys.exit(1)

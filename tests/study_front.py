"""A cycle study's Pareto front as `pressfit study cycle` writes it in summary.json (two samples, known values):
the report's board section shows it (tests/conftest.py builds the report with it, the browser tests read it back)."""

STUDY_FRONT = [{"sample": 2, "speed_scale": 4.0, "acceleration_scale": 1.0, "jerk_scale": 1.0, "descent_scale": 10.0,
                "kp_scale": 2.0, "kd_scale": 1.0, "ki_scale": 1.0, "a4_n": 100.0,
                "cycle_time_s": 3.5, "worst_alignment_error_m": 4e-5, "worst_overshoot_n": 7.0, "within_limits": False},
               {"sample": 0, "speed_scale": 4.0, "acceleration_scale": 1.0, "jerk_scale": 1.0, "descent_scale": 1.0,
                "kp_scale": 1.0, "kd_scale": 1.0, "ki_scale": 1.0, "a4_n": 0.0,
                "cycle_time_s": 6.25, "worst_alignment_error_m": 1e-6, "worst_overshoot_n": 0.5, "within_limits": True}]

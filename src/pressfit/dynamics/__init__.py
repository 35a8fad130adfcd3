"""Multibody dynamics of the press-fit process: masses, natural modes, the closed-loop rigid-leg model, actuators,
controller, contact and the insertion simulation (issue 11)."""

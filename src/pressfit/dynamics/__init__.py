"""Multibody dynamics of the press-fit process: masses, natural modes, the closed-loop rigid-leg model, actuators,
controller, contact and the insertion simulation (issue 11); mjcf: the same rigid-leg machine in MuJoCo (a
second engine checking the multibody model)."""

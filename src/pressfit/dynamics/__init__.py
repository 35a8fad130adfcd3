"""Multibody dynamics of the press-fit process (insertion simulation, modes): not built yet."""

"""Dynamics models of the whole machine behind one interface (:mod:`.base`): the flexible VJM machine
(:mod:`.flexible`); the rigid-leg model (:mod:`pressfit.dynamics.multibody`) is to implement the same interface."""

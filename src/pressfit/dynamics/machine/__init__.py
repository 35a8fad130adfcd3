"""Dynamics models of the whole machine behind one interface (:mod:`.base`): the flexible VJM machine
(:mod:`.flexible`, in a scenario :mod:`.flexible_scenario`) and the rigid-leg model (:mod:`.rigid`); their one
registry, name -> model, is :mod:`.registry`."""

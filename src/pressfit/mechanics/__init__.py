"""Structural mechanics of the machine: the Pinocchio VJM model, statics, condensed stiffness,
compliance, clearance, preload and buckling. No file output here."""

"""Geometry checks: leg interference with Coal."""

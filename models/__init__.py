"""Shipped machine files (package data of pressfit; see pressfit.shipped)."""

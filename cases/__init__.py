"""Shipped case files (package data of pressfit; see pressfit.shipped)."""

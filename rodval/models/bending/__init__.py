"""Quasi-static bending: the reduced model's compiled kernels (banded sweeps and their LU
fallback)."""

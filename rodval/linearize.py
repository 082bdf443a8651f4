"""Superseded by ``rodval.modes`` (linearized modes, static equilibrium, robust spectra of the
published mass matrix); kept as a re-export for existing callers."""
from __future__ import annotations

from .modes import linear_matrices, natural_frequencies

__all__ = ["linear_matrices", "natural_frequencies"]

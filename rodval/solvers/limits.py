"""Sizes the compiled implicit method accepts (kept apart from the compiled loop so that the
driver checks a request without loading it)."""

from __future__ import annotations

#: The largest system the dense Radau IIA takes (N states), by name or by the switch of
#: "auto": its LU factorizations cost O(N^3), about 0.1 s each at this size, and its
#: matrices O(N^2) memory; larger stiff systems stay on DOP853.
MAX_IMPLICIT_SIZE = 600

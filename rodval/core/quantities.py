"""The output quantities, each declared once: name -> unit, index, definition, the scene
output that yields it, the bases it exists on and how each model computes it.

Everything that lists quantities reads ``QUANTITY_TABLE`` (``rodval.core.scene.QUANTITIES``,
``UNITS`` and ``EXPANDS`` are derived from it; the observers, compare, the report and the
table of docs/quantities.md, ``doc_table``). A quantity's one definition is its
``definition``; ``native`` and ``exudyn`` say how the native models (full, reduced, rigid)
and the exudyn model compute it. A *derived* quantity (``tip_deflection``) is a function of
quantities every model already observes (node positions, the base's attitude), defined once
here and called by every observer.

Adding a quantity (docs/architecture.md): its ``Quantity`` here; its value in the native
observer (``rodval/models/systems/observed.py::chain_rows``) and exudyn's
(``reference_models/exudyn_observe.py::observe``); its row of docs/quantities.md is
generated (``python -m rodval.core.quantities --write docs/quantities.md``).
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rodval.core.base import BASE_KINDS

#: What a quantity's k runs over on an n-rod chain (docs/quantities.md).
INDEX_KINDS = ("rod", "node", "hinge", "xy", "root_cm", "scalar")


def index_range(index: str, n: int) -> range:
    """The k an index kind takes on an n-rod chain: "rod" 1..n, "node" 0..n, "hinge"
    0..n-1, "xy" (x, y) and "root_cm" (about the root node, about the centre of mass) 0..1,
    "scalar" 0."""
    spans = {
        "rod": range(1, n + 1),
        "node": range(n + 1),
        "hinge": range(n),
        "xy": range(2),
        "root_cm": range(2),
        "scalar": range(1),
    }
    if index not in spans:
        raise ValueError(f"index must be one of {INDEX_KINDS}, got {index!r}")
    return spans[index]


#: How each index kind reads in the docs table.
INDEX_WORDS = {
    "rod": "rod 1..n",
    "node": "node 0..n",
    "hinge": "hinge 0..n-1",
    "xy": "0, 1 (x, y)",
    "root_cm": "0: root, 1: centre of mass",
    "scalar": "0",
}


@dataclass(frozen=True)
class Quantity:
    """One trajectory quantity.

    ``name`` its column in a trajectory; ``unit`` (SI); ``index`` one of ``INDEX_KINDS``;
    ``definition`` the one definition every model implements; ``output`` the scene output
    that yields it (its own name, or a group: "energy" yields kinetic, potential, energy);
    ``bases`` the base kinds on which it exists; ``missing_in`` the models that do not
    provide it (every other model does; the model names are the registry's,
    ``rodval.models.registry``); ``native``, ``exudyn`` how those models compute it;
    ``audit`` True for the energy audit's quantities, which the audit adds beside an
    observer's "energy" (not yielded by the observer itself)."""

    name: str
    unit: str
    index: str
    definition: str
    output: str = ""
    bases: tuple[str, ...] = BASE_KINDS
    missing_in: tuple[str, ...] = ()
    native: str = ""
    exudyn: str = ""
    audit: bool = False

    def __post_init__(self) -> None:
        if self.index not in INDEX_KINDS:
            raise ValueError(f"Quantity {self.name}: index must be one of {INDEX_KINDS}")
        if not set(self.bases) <= set(BASE_KINDS) or not self.bases:
            raise ValueError(
                f"Quantity {self.name}: bases must be a non-empty subset of {BASE_KINDS}"
            )
        if not self.output:
            object.__setattr__(self, "output", self.name)

    def provided_by(self, model: str, base: str = "pinned") -> bool:
        """Whether model ``model`` (a registry name) outputs it on a base of kind ``base``."""
        return model not in self.missing_in and base in self.bases


#: Every trajectory quantity, once, in output order.
QUANTITY_TABLE: tuple[Quantity, ...] = (
    Quantity("phi", "rad", "rod", "chord angle node k-1 -> node k from the x axis",
             native="coordinate", exudyn="`atan2` of the end nodes' chord, unwrapped in time"),
    Quantity("dphi", "rad/s", "rod", "d phi / dt", native="coordinate rate",
             exudyn="(d x d') / \\|d\\|^2 of the chord d"),
    Quantity("alpha", "rad", "rod", "tangent minus chord angle at the rod's left end",
             native="coordinate (full), quasi-static recovery (reduced), 0 (rigid)",
             exudyn="slope vector of the left end node"),
    Quantity("beta", "rad", "rod", "tangent minus chord angle at the rod's right end",
             native="coordinate (full), quasi-static recovery (reduced), 0 (rigid)",
             exudyn="slope vector of the right end node"),
    Quantity("x", "m", "node", "node position, x", native="from phi (plus node 0's)",
             exudyn="node coordinate"),
    Quantity("y", "m", "node", "node position, y", native="from phi (plus node 0's)",
             exudyn="node coordinate"),
    Quantity("kinetic", "J", "scalar", "kinetic energy T", output="energy",
             native="the model's T", exudyn="beam quadrature"),
    Quantity("potential", "J", "scalar", "potential energy Pi", output="energy",
             native="the model's Pi", exudyn="beam quadrature (plus axial energy)"),
    Quantity("energy", "J", "scalar", "T + Pi", output="energy",
             native="the model's T + Pi", exudyn="beam quadrature"),
    Quantity("work", "J", "scalar", "energy audit: external work W_ext(t)", output="energy",
             native="the driver's power ledger", exudyn="`exudyn_audit`", audit=True),
    Quantity("dissipated", "J", "scalar", "energy audit: dissipated D(t)", output="energy",
             native="the driver's power ledger", exudyn="`exudyn_audit`", audit=True),
    Quantity("energy_residual", "J", "scalar", "energy audit: E(t) - E(0) - W_ext + D",
             output="energy", native="the driver's power ledger", exudyn="`exudyn_audit`", audit=True),
    Quantity("hinge_angle", "rad", "hinge", "D_k = (phi + alpha)_{k+1} - (phi + beta)_k",
             native="from the coordinates", exudyn="continuous tangent angles"),
    Quantity("hinge_moment", "N m", "hinge", "the hinge's moment with the sign of kappa (D - rest)",
             native="spring, damper, stops, lock multiplier",
             exudyn="laws while free, beam root moment when locked"),
    Quantity("angular_momentum", "N m s", "root_cm",
             "k = 0: H_0 about the root node; k = 1: H_c about the centre of mass",
             native="closed form (below)", exudyn="beam quadrature (below)"),
    Quantity("momentum", "N s", "xy",
             "P = sum int v dm, the whole system's (a free base's body included)",
             native="pinned: sum of the rods' p (closed form, below); free base: "
             "m_b v_c + M v_0 + S' (`free_base.momentum`)",
             exudyn="beam quadrature"),
    Quantity("base_position", "m", "xy", "a moving base's centre of mass", output="base",
             bases=("free", "prescribed"), native="coordinates", exudyn="rigid-body node"),
    Quantity("base_velocity", "m/s", "xy", "its velocity", output="base",
             bases=("free", "prescribed"), native="coordinates", exudyn="rigid-body node"),
    Quantity("base_attitude", "rad", "scalar",
             "theta, the body frame's angle from the x axis (hinge 0 is measured from it)",
             output="base", bases=("free", "prescribed"), native="coordinate",
             exudyn="rigid-body node"),
    Quantity("base_rate", "rad/s", "scalar", "theta'", output="base",
             bases=("free", "prescribed"), native="coordinate", exudyn="rigid-body node"),
    Quantity("drive_force", "N", "xy",
             "a prescribed base's force on the chain at node 0, F_d = M a_0 + S'' - F",
             output="drive", bases=("prescribed",), missing_in=("exudyn",),
             native="`chain_base.drive`", exudyn="not measured (refused)"),
    Quantity("drive_moment", "N m", "scalar",
             "its moment about the body's centre, rho x F_d + m_1 (m_1: what hinge 0 passes "
             "to rod 1, its multiplier when held minus its spring and damper's moment)",
             output="drive",
             bases=("prescribed",), missing_in=("exudyn",), native="`chain_base.drive`",
             exudyn="not measured (refused)"),
    Quantity("tip_deflection", "m", "scalar",
             "(r_n - r_0) . e2, the tip's transverse displacement from the straight chain "
             "along the base's axis (below)",
             native="`quantities.tip_deflection` of the nodes and theta",
             exudyn="`quantities.tip_deflection` of the end nodes and the body node's theta"),
)  # fmt: skip

#: name -> Quantity.
QUANTITY: dict[str, Quantity] = {q.name: q for q in QUANTITY_TABLE}

#: The scene outputs, in order: each quantity's own name or its group.
OUTPUTS: tuple[str, ...] = tuple(dict.fromkeys(q.output for q in QUANTITY_TABLE))

#: What a group output yields in a trajectory (the observer's quantities, not the audit's).
GROUPS: dict[str, tuple[str, ...]] = {
    out: tuple(q.name for q in QUANTITY_TABLE if q.output == out and not q.audit)
    for out in OUTPUTS
    if any(q.output == out and q.name != out for q in QUANTITY_TABLE)
}

#: The quantities with one value per rod (k = 1..n), in order.
ROD_QUANTITIES: tuple[str, ...] = tuple(q.name for q in QUANTITY_TABLE if q.index == "rod")

#: Every trajectory quantity's unit.
UNIT: dict[str, str] = {q.name: q.unit for q in QUANTITY_TABLE}

#: The base kinds each scene output exists on.
OUTPUT_BASES: dict[str, tuple[str, ...]] = {
    out: tuple(
        b for b in BASE_KINDS if any(b in q.bases for q in QUANTITY_TABLE if q.output == out)
    )
    for out in OUTPUTS
}

#: How a refused output's base reads (``check_output_bases``).
_BASE_WORDS = {"free": "Base(kind='free', ...)", "prescribed": "Base(kind='prescribed', ...)"}


def quantities_of(outputs: Iterable[str]) -> tuple[str, ...]:
    """The trajectory quantities scene outputs produce: a group its parts, the rest itself."""
    out: list[str] = []
    for q in outputs:
        out.extend(GROUPS.get(q, (q,)))
    return tuple(out)


def quantity_k(name: str, n: int) -> range:
    """The k trajectory quantity ``name`` has on an n-rod chain (ValueError if unknown)."""
    if name not in QUANTITY:
        raise ValueError(f"quantity must be one of {tuple(QUANTITY)}, got {name!r}")
    return index_range(QUANTITY[name].index, n)


def models_with(name: str, models: Iterable[str], base: str = "pinned") -> tuple[str, ...]:
    """Those of ``models`` (registry names) that output quantity ``name`` on ``base``."""
    if name not in QUANTITY:
        raise ValueError(f"quantity must be one of {tuple(QUANTITY)}, got {name!r}")
    return tuple(m for m in models if QUANTITY[name].provided_by(m, base))


def check_output_bases(outputs: Iterable[str], base: str) -> None:
    """A one-line ValueError for an output that does not exist on a base of kind ``base``
    (e.g. "base" on a pinned base), naming the bases it needs."""
    wanted = set(outputs)
    for out in (o for o in OUTPUTS if o in wanted):
        kinds = OUTPUT_BASES[out]
        if base not in kinds:
            need = " or ".join(_BASE_WORDS.get(b, b) for b in kinds)
            words = " or ".join(kinds)
            raise ValueError(f"output '{out}' needs a {words} base ({need})")


def tip_deflection(x: np.ndarray, y: np.ndarray, attitude: np.ndarray | None = None) -> np.ndarray:
    """The tip's transverse displacement (m) in the base's frame: (r_n - r_0) . e2, with
    r_k = (x[..., k], y[..., k]) the node positions (m, node 0..n along the last axis),
    e2 = (-sin theta, cos theta) the base frame's second axis (e1 = (cos theta, sin theta),
    theta = ``attitude`` (rad, the leading axes' shape), None: a pinned base, theta = 0).
    Positive counter-clockwise of e1; 0 for the straight chain along e1. For a chain of
    straight chords at angles phi_k it is sum l_k sin(phi_k - theta)."""
    dx = x[..., -1] - x[..., 0]
    dy = y[..., -1] - y[..., 0]
    if attitude is None:
        return np.asarray(dy, float)
    th = np.asarray(attitude, float)
    return np.asarray(dy * np.cos(th) - dx * np.sin(th), float)


#: The quantities whose largest |value| over a run (its peak, and when) every run records
#: (``SolverStats.peaks``), read between the output times: the native models on their dense
#: output (``rodval.solvers.outputs.PeakGrid``), exudyn on every recorded step.
PEAK_QUANTITIES: tuple[str, ...] = ("hinge_moment", "alpha", "beta", "tip_deflection")


def peak_values(
    times: np.ndarray, observed: dict[str, tuple[np.ndarray, np.ndarray]]
) -> dict[str, list[dict[str, Any]]]:
    """The peaks of the ``PEAK_QUANTITIES`` among ``observed`` (name -> (values (nt, nk), k
    labels), as an observer returns them at ``times`` (s)): per quantity one entry per k,
    ``{"k", "peak": max |value| (the quantity's unit), "t": its time (s)}``; rows holding a
    non-finite value are left out (none left: peak and t None)."""
    out: dict[str, list[dict[str, Any]]] = {}
    for name in PEAK_QUANTITIES:
        if name not in observed:
            continue
        values, ks = observed[name]
        entries: list[dict[str, Any]] = []
        for j, k in enumerate(ks):
            column = np.abs(np.asarray(values, float)[:, j])
            finite = np.flatnonzero(np.isfinite(column))
            if not finite.size:
                entries.append({"k": int(k), "peak": None, "t": None})
                continue
            i = finite[int(np.argmax(column[finite]))]
            entries.append({"k": int(k), "peak": float(column[i]), "t": float(times[i])})
        out[name] = entries
    return out


def impulsive_locks(
    peaks: dict[str, list[dict[str, Any]]], events: Iterable[dict[str, Any]]
) -> None:
    """In ``peaks`` (``peak_values``) of a run whose chords lock plastically (a model without
    bending coordinates, the reduced and rigid models: an ideal latch's whole lock impulse is
    instantaneous, a Dirac in the hinge moment), each hinge that locked (the lock records'
    ``hinge`` and ``impulse_instant``, N m s): its entry holds the lock's impulse
    (``impulse``, the largest |impulse_instant| of its locks, and ``t``, that lock's time)
    and no finite peak (``peak`` None)."""
    if "hinge_moment" not in peaks:
        return
    entries = {int(e["k"]): e for e in peaks["hinge_moment"]}
    for ev in events:
        if "impulse_instant" not in ev or int(ev.get("hinge", -1)) not in entries:
            continue
        entry = entries[int(ev["hinge"])]
        mu = abs(float(ev["impulse_instant"]))
        if mu >= float(entry.get("impulse") or 0.0):
            entry.update(peak=None, t=float(ev["t"]), impulse=mu)


DOC_BEGIN = "<!-- quantity table: generated by python -m rodval.core.quantities --write -->"
DOC_END = "<!-- end of quantity table -->"


def doc_table() -> str:
    """The quantity table of docs/quantities.md (markdown between ``DOC_BEGIN``, ``DOC_END``)."""
    rows = [
        DOC_BEGIN,
        "| quantity | output | k | unit | bases | definition | native (full, reduced, rigid) | exudyn |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for q in QUANTITY_TABLE:
        bases = "all" if q.bases == BASE_KINDS else ", ".join(q.bases)
        cells = (f"`{q.name}`", f"`{q.output}`", INDEX_WORDS[q.index], q.unit, bases,
                 q.definition, q.native, q.exudyn)  # fmt: skip
        rows.append("| " + " | ".join(cells) + " |")
    rows.append(DOC_END)
    return "\n".join(rows)


def with_doc_table(text: str) -> str:
    """``text`` (docs/quantities.md) with its quantity table replaced by ``doc_table()``;
    ValueError when the markers are missing."""
    pattern = re.compile(re.escape(DOC_BEGIN) + ".*?" + re.escape(DOC_END), re.S)
    if not pattern.search(text):
        raise ValueError(
            f"the quantity table's markers ({DOC_BEGIN!r} ... {DOC_END!r}) are missing"
        )
    return pattern.sub(lambda _: doc_table(), text, count=1)


def main(argv: list[str] | None = None) -> int:
    """``--write FILE``: replace the quantity table in FILE; otherwise print it."""
    p = argparse.ArgumentParser(prog="python -m rodval.core.quantities", description=__doc__)
    p.add_argument("--write", type=Path, metavar="FILE", help="replace the quantity table in FILE")
    args = p.parse_args(argv)
    if args.write is not None:
        args.write.write_text(with_doc_table(args.write.read_text()))
    else:
        print(doc_table())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""exudyn's energy audit of the rods' Kelvin-Voigt bending damping at start-up (issue 37;
docs/deployment.md, "Where the lock energy goes", "exudyn's start-up with bending damping").

The deployment_stiff study's scene over its first 0.05 s (no lock yet), exudyn at the
study's three refinements (2, 4, 8 elements per rod at 2e-4, 1e-4, 2.5e-5 s; spectral radius
0), with generalized-alpha's computed initial accelerations (exudyn's default) and without.
Per run: the booked dissipation D(0.05 s) (J) of the audit (c int (dK/dt)^2 ds at the steps,
trapezoidal), beside two candidate bookings from the discrete motion over each step, c int
(Delta K)^2 / h ds and c int (K'_n + K'_n+1) / 2 Delta K ds (the rods' part replaced, the
hinge dampers' kept), the largest rise of E above E(0) over the steps, and the audit's
residual max |R| / energy scale; the full model's D(0.05 s) is the reference.

Run:  PYTHONPATH=. python benchmarks/exudyn_kv_audit.py   (about 10 s)
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
from tabulate import tabulate

import reference_models.exudyn_chain as chain_module
from reference_models.exudyn_audit import energy_parts
from reference_models.exudyn_beam import beam_elements, cross2d
from reference_models.exudyn_chain import ExudynModel
from rodval import simulate
from rodval.core.scene_file import scene_from_dict

STUDY = Path(__file__).resolve().parents[1] / "studies" / "deployment_stiff.toml"
REFINEMENTS = ((2, 2e-4), (4, 1e-4), (8, 2.5e-5))
T_END = 0.05


def scene():
    with STUDY.open("rb") as f:
        d = dict(tomllib.load(f)["scene"])
    d.update(t_end=T_END, times={"num": 51})
    return scene_from_dict(d)


def kv_bookings(sc, E: int, t_rec: np.ndarray, records: dict) -> tuple[float, float, float]:
    """The rods' damping dissipation over the records (J): the audit's trapezoid of
    c int K'^2 ds, c int (Delta K)^2 / h ds and c int mean(K') Delta K ds."""
    qv = {key: (q, v) for key, (q, v, _) in records.items()}
    h = np.diff(t_rec)
    audit = squared = mean = 0.0
    for k, w, _, dS, ddS, Q, V in beam_elements(sc.chain, E, qv):
        c = sc.chain.bending_damping[k]
        r1, r2 = np.einsum("gi,tic->tgc", dS, Q), np.einsum("gi,tic->tgc", ddS, Q)
        v1, v2 = np.einsum("gi,tic->tgc", dS, V), np.einsum("gi,tic->tgc", ddS, V)
        n2 = np.sum(r1**2, -1)
        K = cross2d(r1, r2) / n2
        Kt = (cross2d(v1, r2) + cross2d(r1, v2)) / n2 - 2 * cross2d(r1, r2) * np.sum(
            r1 * v1, -1
        ) / n2**2
        dK = np.diff(K, axis=0)
        audit += c * float(np.sum(np.sum(w * 0.5 * (Kt[1:] ** 2 + Kt[:-1] ** 2), -1) * h))
        squared += c * float(np.sum(np.sum(w * dK**2, -1) / h))
        mean += c * float(np.sum(w * 0.5 * (Kt[1:] + Kt[:-1]) * dK))
    return audit, squared, mean


def main() -> None:
    sc = scene()
    full = simulate(sc, "full")
    reference = float(full["dissipated"][-1, 0])
    captured: dict = {}
    account = chain_module.account

    def spy(scene, E, EA, times, t_rec, records, events, observed):
        captured["run"] = (EA, np.asarray(t_rec), records)
        return account(scene, E, EA, times, t_rec, records, events, observed)

    chain_module.account = spy
    settings = ExudynModel._settings
    rows = []
    try:
        for computed in (True, False):

            def patched(self, scene, computed=computed):
                s = settings(self, scene)
                s.timeIntegration.generalizedAlpha.computeInitialAccelerations = computed
                return s

            ExudynModel._settings = patched  # type: ignore[method-assign]
            for E, h in REFINEMENTS:
                tr = simulate(sc, "exudyn", elements=E, step=h, spectral_radius=0.0)
                EA, t_rec, records = captured["run"]
                D = float(tr["dissipated"][-1, 0])
                audit, squared, mean = kv_bookings(sc, E, t_rec, records)
                energy = energy_parts(sc, E, EA, t_rec, t_rec, records).sum(0)
                rows.append(
                    [
                        "yes" if computed else "no",
                        E,
                        h,
                        D,
                        D - audit + squared,
                        D - audit + mean,
                        float(np.max(energy - energy[0])),
                        tr.stats.energy_residual,
                    ]
                )
    finally:
        chain_module.account = account
        ExudynModel._settings = settings  # type: ignore[method-assign]
    rows.append(["full model", "", "", reference, "", "", "", full.stats.energy_residual])
    headers = [
        "initial acc.",
        "el.",
        "h (s)",
        "D audit (J)",
        "D (dK)^2/h",
        "D mean K' dK",
        "max E-E0 (J)",
        "residual",
    ]
    print(f"deployment_stiff, first {T_END} s: booked dissipation D({T_END} s)")
    formats = ("", "", ".2g", ".6g", ".6g", ".6g", ".4g", ".3g")
    print(tabulate(rows, headers, tablefmt="github", floatfmt=formats))


if __name__ == "__main__":
    main()

"""The study report's Modes section (a study with [modes]): every model's linearized natural
frequencies, the MAC pairing against the reference and the report cases' mode shapes, from
``modes.csv``, ``mac.csv`` and ``mode_shapes.csv``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rodval.core.modes import Modes
from rodval.report.figures import plot_modes
from rodval.report.markdown import to_markdown
from rodval.report.study_figures import figure_slug

#: Columns of ``mac.csv`` shown in the report, when present.
MAC_REPORT_COLUMNS = (
    "case",
    "model",
    "reference",
    "mode_a",
    "mode_b",
    "omega_a",
    "omega_b",
    "rel_gap",
    "mac",
)


def modes_from_tables(freq: pd.DataFrame, shapes: pd.DataFrame, case: str, model: str) -> Modes:
    """One model's modes of one case rebuilt from the modes and mode_shapes tables."""
    f = freq[(freq["case"] == case) & (freq["model"] == model)].sort_values("mode")
    sh = shapes[(shapes["case"] == case) & (shapes["model"] == model)]

    def arr(kind: str, mode: int) -> np.ndarray:
        """The values of ``kind`` (a mode_shapes kind) of ``mode``, by node or hinge k."""
        part = sh[(sh["kind"] == kind) & (sh["mode"] == mode)].sort_values("k")
        values: np.ndarray = part["value"].to_numpy(float)
        return values

    x0, y0 = arr("node_x0", 0), arr("node_y0", 0)
    modes = [int(m) for m in f["mode"]]
    return Modes(
        model=model,
        about="",
        omega=f["omega_rad_s"].to_numpy(float),
        damping=f["damping_ratio"].to_numpy(float),
        dx=np.array([arr("node_dx", m) for m in modes]),
        dy=np.array([arr("node_dy", m) for m in modes]),
        hinge=np.array([arr("hinge", m) for m in modes]),
        phi0=np.arctan2(np.diff(y0), np.diff(x0)),
        l=np.hypot(np.diff(x0), np.diff(y0)),
    )


def modes_section(out: Path, fig_dir: Path, meta: dict[str, Any]) -> list[str]:
    """Frequencies of every model, the MAC pairing against the reference and mode-shape
    figures of the report cases, when the study asked for modes ([modes])."""
    if not (out / "modes.csv").is_file():
        return []
    freq = pd.read_csv(out / "modes.csv")
    lines = [
        "## Modes\n",
        "Linearized natural frequencies (rad/s) of every model "
        "(`modes.csv`; damping ratios there), and each model's modes paired by shape with "
        f"`{meta['reference']}`'s (modal assurance criterion, `mac.csv`).\n",
    ]
    if "omega_rad_s" in freq:
        ok = freq[freq["omega_rad_s"].notna()]
        wide = ok.pivot_table(
            index=["case", "mode"], columns="model", values="omega_rad_s", sort=False
        )
        lines.append(to_markdown(wide.reset_index(), ".6g"))
    if "error" in freq and freq["error"].notna().any():
        failed = freq[freq["error"].notna()][["case", "model", "error"]]
        lines += ["Modal analyses that failed:\n", to_markdown(failed)]
    mac_path = out / "mac.csv"
    if mac_path.is_file() and mac_path.stat().st_size > 1:
        mac = pd.read_csv(mac_path)
        lines.append(to_markdown(mac[[c for c in MAC_REPORT_COLUMNS if c in mac]], ".4g"))
    shapes_path = out / "mode_shapes.csv"
    if shapes_path.is_file() and "omega_rad_s" in freq:
        lines += _mode_figures(freq, pd.read_csv(shapes_path), fig_dir, meta)
    return lines


def _mode_figures(
    freq: pd.DataFrame, shapes: pd.DataFrame, fig_dir: Path, meta: dict[str, Any]
) -> list[str]:
    """Per report case, the first mode shapes of the reference (or, when its analysis failed,
    of the first model that has modes)."""
    lines = []
    for cid in meta["report"]["cases"]:
        have = set(freq[(freq["case"] == cid) & freq["omega_rad_s"].notna()]["model"])
        model = meta["reference"] if meta["reference"] in have else next(iter(have), None)
        if model is None:
            continue
        m = modes_from_tables(freq, shapes, cid, model)
        fig = plot_modes(
            m,
            fig_dir / f"modes_{figure_slug(cid)}.png",
            title=f"case {cid}: {model}, first modes",
        )
        lines.append(f"![mode shapes, case {cid}](figures/{fig.name})\n")
    return lines

"""Scenes from TOML files or plain dicts (the format studies reuse for their base scene), and
the complete resolved scene as a dict (``scene_to_dict``: run records, reruns).

Every key, with its unit, meaning, default and allowed range: ``docs/scene_file.md``.
Every error is a ValueError that names the file and the offending key.
"""

from __future__ import annotations

import dataclasses
import inspect
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from rodval.core.base import PINNED, Base
from rodval.core.checks import check_keys
from rodval.core.loads import LOAD_FACTORIES
from rodval.core.profiles import resolve_profiles
from rodval.core.scene import (
    DEFAULT_NUM_TIMES,
    MAX_TIMES,
    QUANTITIES,
    Chain,
    InitialState,
    Latch,
    Scene,
    Stop,
    output_times,
    paper_scene,
)

BASES = ("paper",)
TOP_KEYS = {
    "base",
    "name",
    "n",
    "t_end",
    "times",
    "outputs",
    "chain",
    "loads",
    "initial",
    "latches",
    "stops",
}
LATCH_KEYS = ("hinge", "angle", "direction", "window")
STOP_KEYS = ("hinge", "angle", "side", "stiffness", "damping")
CHAIN_KEYS = set(Chain.FIELDS)
INITIAL_KEYS = {"phi", "dphi", "alpha", "beta", "dalpha", "dbeta"}
TIMES_KEYS = {"start", "stop", "num"}


def _times(value: Any, t_end: float, where: str) -> np.ndarray | None:
    if value is None:
        return None
    if isinstance(value, dict):
        check_keys(value, TIMES_KEYS, f"{where} key 'times'")
        num = value.get("num", DEFAULT_NUM_TIMES)
        if isinstance(num, bool) or not isinstance(num, int):
            raise ValueError(
                f"{where} key 'times': num must be an integer >= 1 and <= {MAX_TIMES}, got {num!r}"
            )
        if not 1 <= num <= MAX_TIMES:
            raise ValueError(f"{where} key 'times': num must be >= 1 and <= {MAX_TIMES}, got {num}")
        for key in ("start", "stop"):
            v = value.get(key)
            if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float))):
                raise ValueError(f"{where} key 'times.{key}': must be a number (s), got {v!r}")
        return output_times(float(value.get("start", 0.0)), float(value.get("stop", t_end)), num)
    if isinstance(value, (list, tuple)):
        if any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value):
            raise ValueError(f"{where} key 'times': must be a list of numbers (s), got {value!r}")
        if len(value) > MAX_TIMES:
            raise ValueError(
                f"{where} key 'times': at most {MAX_TIMES} output times, got {len(value)}"
            )
        return np.array([float(v) for v in value])
    raise ValueError(
        f"{where} key 'times': must be a list of seconds or a table {{start, stop, num}}"
    )


def _load(spec: dict, n: int, where: str):
    if not isinstance(spec, dict) or "type" not in spec:
        raise ValueError(f"{where}: each load needs a 'type' (one of {', '.join(LOAD_FACTORIES)})")
    kind = spec["type"]
    if not isinstance(kind, str) or kind not in LOAD_FACTORIES:
        raise ValueError(
            f"{where}: load type must be one of {', '.join(LOAD_FACTORIES)}, got {kind!r}"
        )
    args = {k: v for k, v in spec.items() if k != "type"}
    if args.get("node") == "last":
        args["node"] = n
    factory = LOAD_FACTORIES[kind]
    allowed = [p for p in inspect.signature(factory).parameters]
    unknown = sorted(set(args) - set(allowed))
    if unknown:
        raise ValueError(
            f"{where}: unexpected keyword {unknown[0]!r} for load {kind!r} "
            f"(allowed: {', '.join(allowed)})"
        )
    if "node" not in args:
        raise ValueError(f"{where}: load {kind!r} needs 'node' (1..n or \"last\")")
    return factory(**args)


def _table_items(d: dict, key: str, cls: type, keys: tuple[str, ...], where: str) -> list:
    """``[[latches]]`` / ``[[stops]]`` tables as Latch / Stop objects."""
    items = d.get(key, [])
    if not isinstance(items, list):
        raise ValueError(f"key '{key}' must be an array of tables [[{key}]]")
    out = []
    for i, spec in enumerate(items):
        place = f"{where} [[{key}]] #{i + 1}"
        check_keys(spec, set(keys), place)
        try:
            out.append(cls(**spec))
        except TypeError as exc:
            raise ValueError(f"{place}: {exc}") from None
    return out


def scene_from_dict(d: dict, where: str = "scene") -> Scene:
    """Build and validate a Scene from the dict form (see module docstring).

    Every error is a ValueError that names ``where`` (a file name) and the offending key.
    """
    check_keys(d, TOP_KEYS, where)
    base = d.get("base", "paper")
    body = PINNED
    if isinstance(base, dict):  # a [base] table: the body node 0 belongs to, on the paper's scene
        body = Base.from_dict(base, f"{where} [base]")
    elif base not in BASES:
        raise ValueError(
            f"{where} key 'base': must be one of {BASES} or a [base] table, got {base!r}"
        )
    try:
        n = d.get("n", 8)
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ValueError(f"key 'n' (number of rods) must be an integer >= 1, got {n!r}")
        t_end = d.get("t_end", 2.0)
        if isinstance(t_end, bool) or not isinstance(t_end, (int, float)):
            raise ValueError(f"key 't_end' (horizon) must be a number > 0 s, got {t_end!r}")
        # the base's chain, loads and outputs; its output times are the file's (one here, so
        # that memory is checked once, on the scene's own times)
        scene = paper_scene(n, t_end=float(t_end), times=[float(t_end)])
        chain_spec = d.get("chain", {})
        check_keys(chain_spec, CHAIN_KEYS, f"{where} [chain]")
        chain_spec = resolve_profiles(chain_spec, n, f"{where} [chain]")
        chain = (
            Chain(**{**scene.chain.as_dict(), **chain_spec}, _n=n) if chain_spec else scene.chain
        )
        loads = scene.loads
        if "loads" in d:
            if not isinstance(d["loads"], list):
                raise ValueError("key 'loads' must be an array of tables [[loads]]")
            loads = tuple(
                _load(s, n, f"{where} [[loads]] #{i + 1}") for i, s in enumerate(d["loads"])
            )
        init_spec = d.get("initial", {})
        check_keys(init_spec, INITIAL_KEYS, f"{where} [initial]")
        init_spec = resolve_profiles(init_spec, n, f"{where} [initial]")
        outputs = d.get("outputs", scene.outputs)
        if isinstance(outputs, str) or not isinstance(outputs, (list, tuple)):
            raise ValueError(f"key 'outputs' must be a list from {QUANTITIES}, got {outputs!r}")
        latches = tuple(_table_items(d, "latches", Latch, LATCH_KEYS, where))
        stops = tuple(_table_items(d, "stops", Stop, STOP_KEYS, where))
        return Scene(
            chain=chain,
            loads=loads,
            latches=latches,
            stops=stops,
            t_end=float(t_end),
            times=_times(d.get("times"), float(t_end), where),
            outputs=tuple(outputs),
            initial=InitialState(**init_spec),
            name=d.get("name", scene.name),
            base=body,
        )
    except ValueError as exc:
        msg = str(exc)
        raise ValueError(msg if msg.startswith(where) else f"{where}: {msg}") from None


def read_scene_document(source: str | Path) -> dict[str, Any]:
    """The scene document (dict form) of ``"paper"`` or a TOML scene file, not yet validated."""
    if str(source) in BASES:
        return {"base": str(source)}
    path = Path(source)
    if not path.is_file():
        raise ValueError(f"SCENE must be 'paper' or an existing TOML file, got {str(source)!r}")
    try:
        data = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: malformed TOML: {exc}") from None
    data.setdefault("name", path.stem)
    return anchor_load_files(data, path.parent)


def anchor_load_files(doc: dict[str, Any], folder: Path) -> dict[str, Any]:
    """``doc`` with each load's relative ``file`` taken relative to ``folder`` (the folder of
    the file that names it), so that a scene or study file finds its tabulated histories
    wherever it is run from. Anything else is left for scene_from_dict to check."""
    loads = doc.get("loads")
    if not isinstance(loads, list):
        return doc
    anchored = [
        {**load, "file": str(folder / load["file"])}
        if isinstance(load, dict)
        and isinstance(load.get("file"), str)
        and not Path(load["file"]).is_absolute()
        else load
        for load in loads
    ]
    return {**doc, "loads": anchored}


def load_scene(source: str | Path) -> Scene:
    """``"paper"`` (the paper's example) or the path of a TOML scene file."""
    return scene_from_dict(read_scene_document(source), where=str(source))


def with_horizon(doc: dict[str, Any], t_end: float, where: str) -> Scene:
    """The scene of ``doc`` over a new horizon ``t_end`` (s): output times the document lists
    are kept up to t_end (ValueError if none is left); without output times the default grid
    of the new horizon is used. Nothing else changes."""
    if "times" not in doc:
        return scene_from_dict({**doc, "t_end": t_end}, where=where)
    scene = scene_from_dict(doc, where=where)
    keep = scene.times[scene.times <= t_end]
    if keep.size == 0:
        raise ValueError(
            f"{where}: --t-end {t_end:g} s leaves none of the scene's output times "
            f"(the first is {scene.times[0]:g} s); give --times as well"
        )
    return scene.with_(t_end=t_end, times=keep)


def scene_to_dict(scene: Scene) -> dict[str, Any]:
    """The complete resolved scene in the scene-file format (chain arrays, loads with their
    parameters, initial state, output times, outputs): ``scene_from_dict`` rebuilds the same
    scene from it, bit for bit. A load that is a plain Python callable has no such form: it
    is recorded as ``{"type": "callable", "node": k}``, which ``scene_from_dict`` refuses."""
    init = scene.initial.resolve(scene.n)
    return {
        "name": scene.name,
        "n": scene.n,
        "t_end": scene.t_end,
        "times": [float(t) for t in scene.times],
        "outputs": list(scene.outputs),
        "chain": scene.chain.as_dict(),
        "loads": [{"type": f.name, "node": f.node, **f.params} for f in scene.loads],
        "initial": {k: v.tolist() for k, v in init.items()},
        "latches": [dataclasses.asdict(latch) for latch in scene.latches],
        "stops": [dataclasses.asdict(stop) for stop in scene.stops],
        # a free body only: a pinned scene's dict (and every record made of it) is unchanged
        **({"base": scene.base.as_dict()} if scene.base.free else {}),
    }


#: Keys of a scene dict that label or observe a scene without changing what is simulated:
#: runs that differ only there are runs of the same scene (compared on their common
#: quantities and output times).
LABEL_KEYS = ("name", "outputs")


def scene_differences(a: dict[str, Any], b: dict[str, Any]) -> list[str]:
    """The keys in which two scene dicts (``scene_to_dict``) differ, dotted for the tables
    (``"chain.EI"``, ``"initial.phi"``, ``"loads"``), sorted; labels (``LABEL_KEYS``) aside.
    Empty when both describe the same simulation."""
    out = []
    for key in sorted((set(a) | set(b)) - set(LABEL_KEYS)):
        va, vb = a.get(key), b.get(key)
        if isinstance(va, dict) and isinstance(vb, dict):
            out += [f"{key}.{k}" for k in sorted(set(va) | set(vb)) if va.get(k) != vb.get(k)]
        elif va != vb:
            out.append(key)
    return out

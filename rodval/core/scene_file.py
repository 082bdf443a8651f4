"""Scenes from TOML files or plain dicts (the format studies reuse for their base scene), and
the complete resolved scene as a dict (``scene_to_dict``: run records, reruns).

A document holds what it says: an omitted key is physically neutral (no loads, no node
masses, hinge springs or dampers, straight at rest) or, for ``n``, ``t_end`` and the rods'
``l``, ``m``, ``EI``, an error naming it; ``based_on = "paper"`` fills in the paper's example.
Every key, with its unit, meaning, default and allowed range: ``docs/scene_file.md``.
Every error is a ValueError that names the file and the offending key.
"""

from __future__ import annotations

import copy
import inspect
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from rodval.core.base import BASE_KINDS, PINNED, Base
from rodval.core.checks import check_keys
from rodval.core.damping import (
    PANEL,
    RATIO_KEYS,
    DampingRequest,
    bending_damping_for_ratio,
    damping_request,
)
from rodval.core.hinges import HINGE_ITEMS
from rodval.core.loads import LOAD_FACTORIES, NodalForce, pulse
from rodval.core.profiles import resolve_profiles
from rodval.core.resources import check_rods
from rodval.core.scene import (
    DEFAULT_NUM_TIMES,
    MAX_TIMES,
    UNIFORM_DEFAULTS,
    Chain,
    Grid,
    InitialState,
    Scene,
)
from rodval.core.scene_keys import SCENE_KEYS, check_types, merge_documents, missing_key, set_path
from rodval.core.settings import SETTING_NAMES

#: The scenes a file may be ``based_on`` by name: what the file omits takes that scene's
#: values. In a file, ``based_on`` may also be the path of another scene file
#: (``read_scene_document``).
BASED_ON = ("paper",)
#: Most scene files one ``based_on`` chain may pass through (the file itself included).
MAX_BASED_ON_DEPTH = 16
#: The paper example's number of rods and horizon (s) (``paper_scene``'s defaults).
PAPER_N = 8
PAPER_T_END = 2.0
#: Rod data without a neutral value: a file states them (or is ``based_on`` a scene).
REQUIRED_CHAIN = {
    "l": "rod length, m",
    "m": "mass per length, kg/m",
    "EI": "bending stiffness, N m^2",
}
#: The neutral values of the other chain fields: no node masses (kg), hinge springs
#: (N m/rad) or dampers (N m s/rad), springs relaxed straight (rad), no bending damping
#: (N m^2 s).
NEUTRAL_CHAIN: dict[str, float] = dict(
    mu=0.0, kappa=0.0, nu=0.0, rest_angle=0.0, bending_damping=0.0
)
#: The outputs of a file that names none (``Scene``'s default; outputs are not physics).
DEFAULT_OUTPUTS: tuple[str, ...] = Scene.outputs
#: The keys of a scene document (``SCENE_KEYS``'s tables).
TOP_KEYS = set(SCENE_KEYS)
CHAIN_KEYS = set(Chain.FIELDS)
INITIAL_KEYS = set(InitialState.KEYS)
TIMES_KEYS = {"start", "stop", "num"}


def _times(value: Any, where: str) -> np.ndarray | Grid | None:
    """The output times (s) of ``times`` (its type checked, ``check_types``): a list, a table
    {start, stop, num} (a ``Grid`` the Scene resolves on its horizon), or None (the scene's
    default grid)."""
    if value is None:
        return None
    if isinstance(value, list):
        if len(value) > MAX_TIMES:
            raise ValueError(
                f"{where} key 'times': at most {MAX_TIMES} output times, got {len(value)}"
            )
        return np.array([float(v) for v in value])
    check_keys(value, TIMES_KEYS, f"{where} key 'times'")
    num = value.get("num", DEFAULT_NUM_TIMES)
    if not 1 <= num <= MAX_TIMES:
        raise ValueError(f"{where} key 'times': num must be >= 1 and <= {MAX_TIMES}, got {num}")
    return Grid(float(value.get("start", 0.0)), value.get("stop"), num)


def _load(spec: dict[str, Any], n: int, where: str) -> NodalForce:
    """A ``[[loads]]`` table (its types and required keys checked, ``check_types``) as the
    force its law's factory (``LOAD_FACTORIES``) builds."""
    kind = spec["type"]
    if kind not in LOAD_FACTORIES:
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


def _missing(key: str, what: str) -> ValueError:
    """The one-line error of a required key the document omits (``where`` is added by
    ``scene_from_dict``)."""
    return ValueError(
        f"key '{key}' ({what}) is missing; give it, or write based_on = \"paper\" to take "
        "the paper example's values for every key the file omits"
    )


def _based_on(d: dict[str, Any], where: str) -> str | None:
    """The document's ``based_on`` (one of ``BASED_ON``) or None."""
    based_on = d.get("based_on")
    if based_on is not None and (not isinstance(based_on, str) or based_on not in BASED_ON):
        raise ValueError(
            f"{where} key 'based_on': must be one of {BASED_ON} (the scene whose values fill "
            "in what the file omits) or, in a scene file, the path of another scene file "
            f"(resolved when the file is read), got {based_on!r}"
        )
    return based_on


def _base_advice(base: str) -> str:
    """What a top-level string ``base = ...`` was meant to say, so that no file silently
    changes meaning: a base kind is written in the [base] table (``[base] kind = "free"``),
    the scene a file starts from is ``based_on`` (the old spelling was ``base = "paper"``)."""
    if base in BASE_KINDS:
        return (
            f"base = {base!r} is not a table; the body node 0 belongs to is the [base] table: "
            f'write [base] kind = "{base}" (with its keys, docs/base.md)'
        )
    if base in BASED_ON:
        return (
            f"base = {base!r} no longer names the scene the file starts from; write "
            f'based_on = "{base}" for that ([base] is a table: the body node 0 belongs to)'
        )
    return (
        f"must be the [base] table (the body node 0 belongs to: [base] kind = one of "
        f"{', '.join(BASE_KINDS)}), got the string {base!r}; the scene a file starts from is "
        "based_on"
    )


def _count(d: dict[str, Any], based_on: str | None) -> int:
    """``n``, the number of rods: an integer >= 1 (the paper's 8 with ``based_on``)."""
    if "n" not in d and based_on is None:
        raise _missing("n", "number of rods")
    n = d.get("n", PAPER_N)
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ValueError(f"key 'n' (number of rods) must be an integer >= 1, got {n!r}")
    check_rods(n)  # before any n-sized list (a profile) exists
    return n


def _horizon(d: dict[str, Any], based_on: str | None) -> Any:
    """``t_end``, the horizon (s), as given (the Scene checks it: ``check_horizon``); the
    paper's 2 s with ``based_on``."""
    if "t_end" not in d and based_on is None:
        raise _missing("t_end", "horizon, s")
    return d.get("t_end", PAPER_T_END)


def _chain(
    d: dict[str, Any], n: int, based_on: str | None, where: str
) -> tuple[Chain, DampingRequest | None]:
    """The ``[chain]`` table over the paper's values (``based_on``) or the neutral ones; a rod
    field without a neutral value (``REQUIRED_CHAIN``) must be given. With the damping's
    ratio form, also its request (``rodval.core.damping``): a panel ratio is converted here;
    a deployed one leaves c = 0 for the models layer to convert (``DampingRequest.pending``)."""
    spec = dict(d.get("chain", {}))
    check_keys(spec, CHAIN_KEYS, f"{where} [chain]")
    request = _damping_request(spec, where)
    spec = resolve_profiles(spec, n, f"{where} [chain]")
    defaults = UNIFORM_DEFAULTS if based_on == "paper" else NEUTRAL_CHAIN
    for key, what in REQUIRED_CHAIN.items():
        if key not in spec and key not in defaults:
            raise _missing(f"chain.{key}", what)
    chain = Chain(**{**defaults, **spec}, _n=n)
    if request is None or request.of != PANEL:
        return chain, request
    ratio = list(request.ratio) if isinstance(request.ratio, tuple) else request.ratio
    c = bending_damping_for_ratio(ratio, chain.l, chain.m, chain.EI)
    return chain.with_(bending_damping=c), request


def _damping_request(spec: dict[str, Any], where: str) -> DampingRequest | None:
    """The request of ``[chain] bending_damping = { ratio = ..., of = ... }`` (removed from
    ``spec``: the chain gets the converted N m^2 s, ``rodval.core.damping``), or None when
    the damping is given in N m^2 s (a number, a list or a profile: a table with neither
    ``ratio`` nor ``of``). A table with ``of`` and no ``ratio`` is refused naming the ratio."""
    value = spec.get("bending_damping")
    if not isinstance(value, dict) or not set(value) & set(RATIO_KEYS):
        return None
    if "ratio" not in value:
        raise missing_key(where, "chain.bending_damping.ratio")
    request = damping_request(value, where)
    del spec["bending_damping"]
    return request


def _loads(d: dict[str, Any], n: int, based_on: str | None, where: str) -> tuple[NodalForce, ...]:
    """The ``[[loads]]`` tables; omitted: none (the paper's pulse at node n with
    ``based_on``)."""
    if "loads" not in d:
        return (pulse(n),) if based_on == "paper" else ()
    return tuple(_load(s, n, f"{where} [[loads]] #{i + 1}") for i, s in enumerate(d["loads"]))


def _refuse_settings(d: dict[str, Any], where: str) -> None:
    """An integrator setting written among a scene's keys (``rtol = 1e-6`` in a scene file or a
    study's [scene]) is refused saying where it goes, before the keys' own check lists the
    scene keys only."""
    settings = sorted(set(d) & set(SETTING_NAMES)) if isinstance(d, dict) else []
    if settings:
        name = settings[0]
        raise ValueError(
            f"{where} key '{name}': an integrator setting, not a scene value; give it on the "
            f"command line (--set {name}=...) or in a study's [integrator] or [models.LABEL]"
        )


def scene_from_dict(d: dict[str, Any], where: str = "scene") -> Scene:
    """Build and validate a Scene from the dict form (``docs/scene_file.md``).

    The scene holds what ``d`` says: an omitted key is neutral (no loads, no node masses,
    hinge springs or dampers, straight at rest, pinned, the default output times) or, for
    ``n``, ``t_end`` and the rods' ``l``, ``m``, ``EI``, an error; with ``based_on = "paper"``
    every omitted key takes the paper example's value (``paper_scene``). Every error is a
    ValueError that names ``where`` (a file name) and the offending key.
    """
    _refuse_settings(d, where)
    check_keys(d, TOP_KEYS, where)
    if isinstance(d.get("base"), str):  # the old spelling of based_on, or a base kind
        raise ValueError(f"{where} key 'base': {_base_advice(d['base'])}")
    check_types(d, where)
    based_on = _based_on(d, where)
    body = Base.from_dict(d["base"], f"{where} [base]") if "base" in d else PINNED
    try:
        n = _count(d, based_on)
        t_end = _horizon(d, based_on)
        chain, damping = _chain(d, n, based_on, where)
        loads = _loads(d, n, based_on, where)
        init_spec = d.get("initial", {})
        check_keys(init_spec, INITIAL_KEYS, f"{where} [initial]")
        init_spec = resolve_profiles(init_spec, n, f"{where} [initial]")
        outputs = d.get("outputs", DEFAULT_OUTPUTS)
        items: dict[str, Any] = {t: kind.from_tables(d, where) for t, kind in HINGE_ITEMS.items()}
        return Scene(
            chain=chain,
            loads=loads,
            **items,
            t_end=t_end,
            times=_times(d.get("times"), where),
            outputs=tuple(outputs),
            initial=InitialState(**init_spec),
            name=d.get("name", f"paper-n{n}" if based_on == "paper" else "scene"),
            base=body,
            damping=damping,
        )
    except ValueError as exc:
        msg = str(exc)
        raise ValueError(msg if msg.startswith(where) else f"{where}: {msg}") from None


def read_scene_document(source: str | Path) -> dict[str, Any]:
    """The scene document (dict form) of ``"paper"`` or a TOML scene file, not yet validated.
    A file ``based_on`` another scene file (a path relative to its own folder) is laid over
    that file's document (``merge_documents``: sections key by key, the later file winning),
    down the chain of files (at most ``MAX_BASED_ON_DEPTH``; a loop is refused naming the
    files); its name is its own ``name`` or its file name."""
    if str(source) in BASED_ON:
        return {"based_on": str(source)}
    path = Path(source)
    if not path.is_file():
        raise ValueError(f"SCENE must be 'paper' or an existing TOML file, got {str(source)!r}")
    data, _ = scene_file_document(path)
    data.setdefault("name", path.stem)
    return data


def scene_file_document(
    path: Path, chain: tuple[Path, ...] = ()
) -> tuple[dict[str, Any], tuple[Path, ...]]:
    """The document of the scene file ``path`` with its ``based_on`` file (if any) resolved,
    and the files read (``path`` first, then the files it is based on); ``chain``: the files
    that led here (for loops and depth)."""
    try:
        data = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: malformed TOML: {exc}") from None
    except OSError as exc:
        raise ValueError(f"{path}: cannot read: {exc.strerror}") from None
    data = anchor_load_files(data, path.parent)
    parent = data.get("based_on")
    if not isinstance(parent, str) or parent in BASED_ON:
        return data, (path,)
    here = (*chain, path)
    target = path.parent / parent
    names = " -> ".join(str(p) for p in (*here, target))
    if not target.is_file():
        raise ValueError(
            f"{path} key 'based_on': {str(target)!r} is not a scene file (a based_on path is "
            f'relative to the folder of the file that names it; or "paper")'
        )
    if any(target.resolve() == p.resolve() for p in here):
        raise ValueError(f"{path} key 'based_on': the files start from each other: {names}")
    if len(here) >= MAX_BASED_ON_DEPTH:
        raise ValueError(
            f"{path} key 'based_on': more than {MAX_BASED_ON_DEPTH} files start from one "
            f"another ({names})"
        )
    earlier, files = scene_file_document(target, here)
    _check_earlier(earlier, target, path)
    earlier.pop("name", None)  # a file's name is its own (or its file name), never inherited
    later = {k: v for k, v in data.items() if k != "based_on"}
    return merge_documents(earlier, later), (path, *files)


def _check_earlier(earlier: dict[str, Any], target: Path, path: Path) -> None:
    """The scene of the file ``target`` (its document ``earlier``, its own ``based_on``
    resolved), which ``path`` is based on, built once to check it: an error there is
    ``target``'s, named so (a one-line ValueError starting with ``target``), never the error
    of the file that names it."""
    try:
        scene_from_dict(earlier, where=str(target))
    except ValueError as exc:
        raise ValueError(f"{exc} ({path} is based on it)") from None


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


def with_overrides(doc: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """A copy of the scene document ``doc`` with each value of ``overrides`` (dotted path ->
    value, ``set_path``: a study grid's paths) set; ``doc`` is not changed. The values are
    checked when the scene is built, like the file's. ValueError naming ``--set <path>`` when
    a path runs into a value that is not a table or a list."""
    out = copy.deepcopy(doc)
    for path, value in overrides.items():
        try:
            set_path(out, path, value)
        except ValueError as exc:
            raise ValueError(f"--set {exc}") from None
    return out


def load_scene(source: str | Path) -> Scene:
    """``"paper"`` (the paper's example, ``{"based_on": "paper"}``) or the path of a TOML
    scene file."""
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
    """The complete resolved scene in the scene-file format (every key: chain arrays, loads
    with their parameters, initial state, output times, outputs; a free base): it is based on
    nothing, and ``scene_from_dict`` rebuilds the same scene from it, bit for bit. A load
    that is a plain Python callable has no such form: it is recorded as
    ``{"type": "callable", "node": k}``, which ``scene_from_dict`` refuses. A deployed
    damping request not yet converted (``DampingRequest.pending``) is recorded as the request
    ``{ ratio, of = "deployed" }`` in place of its placeholder c, so that the scene rebuilt
    from the dict converts it again; a converted one as its c (N m^2 s)."""
    init = scene.initial.resolve(scene.n)
    chain = scene.chain.as_dict()
    if scene.damping is not None and scene.damping.pending:
        chain["bending_damping"] = scene.damping.as_dict()  # type: ignore[assignment]
    return {
        "name": scene.name,
        "n": scene.n,
        "t_end": scene.t_end,
        "times": [float(t) for t in scene.times],
        "outputs": list(scene.outputs),
        "chain": chain,
        "loads": [{"type": f.name, "node": f.node, **f.params} for f in scene.loads],
        "initial": {k: v.tolist() for k, v in init.items()},
        **{t: [item.as_dict() for item in getattr(scene, t)] for t in HINGE_ITEMS},
        # a free body only: a pinned scene's dict (and every record made of it) is unchanged
        **({"base": scene.base.as_dict()} if scene.base.moving else {}),
    }


def scene_to_file_table(scene: Scene, where: str = "scene") -> dict[str, Any]:
    """The scene as a scene file's table (a study's ``[scene]``): ``scene_to_dict`` with every
    None left out, since None means the default (a latch's ``direction``: towards its angle;
    its ``window``: the first bending period, s) and TOML has no null; ``scene_from_dict``
    rebuilds the same scene from it. A load that is a plain Python callable has no file form:
    a one-line ValueError naming ``where.loads[i]``."""
    for i, load in enumerate(scene.loads):
        if load.name not in LOAD_FACTORIES:
            raise ValueError(
                f"{where}.loads[{i}]: the load on node {load.node} is a plain Python callable, "
                "which a scene or study file cannot hold; build it with a load law of "
                f"rodval.core.loads ({', '.join(LOAD_FACTORIES)})"
            )
    table: dict[str, Any] = _without_none(scene_to_dict(scene))
    return table


def _without_none(value: Any) -> Any:
    """``value`` with the None entries of its tables left out, at every depth."""
    if isinstance(value, dict):
        return {k: _without_none(v) for k, v in value.items() if v is not None}
    if isinstance(value, list):
        return [_without_none(v) for v in value]
    return value


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

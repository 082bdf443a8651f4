"""Every key of a scene file, its type, unit and allowed values: one definition (``SCENE_KEYS``)
that drives the type check of every scene document at the boundary (``check_types``: a
one-line ValueError naming the key by its dotted path before anything is built) and the key
table of ``docs/scene_file.md`` (``doc_table``; ``python -m rodval.core.scene_keys
--doc-table`` prints it, ``--write docs/scene_file.md`` puts it in place). The ranges are
enforced by the objects the values build (``Chain``, ``Base``, ``Latch``, ...); this table
states them. A hinge item's keys are its own (``rodval.core.hinges.HINGE_ITEMS``: a
``[[latches]]`` table's are ``Latch.KEYS``).

Dotted paths into a scene document (``set_path``: a study grid's ``scene.chain.EI``, the
command line's ``--set chain.EI=2e8``; in a list ``*`` is every element, an integer one), and
the merge of two documents (``merge_documents``: a scene file ``based_on`` another, a study's
[scene] over the file it names): the sections (``[chain]``, ``[initial]``, ``[base]``,
``[base.motion]``) merge key by key (a ``[base]`` of another ``kind`` replaces the earlier
base whole), every other value (numbers, lists, arrays of tables, inline tables such as
profiles, motion laws or ``times``) replaces the earlier one whole.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path
from typing import Any

from rodval.core.hinges import HINGE_ITEMS
from rodval.core.keys import (
    INTEGER,
    NODE,
    NUMBER,
    NUMBER_OR_NUMBERS,
    NUMBERS,
    PAIR,
    ROD,
    STRING,
    STRINGS,
    TABLE,
    TABLES,
    TIMES,
    Key,
)


def _rod(unit: str, allowed: str) -> Key:
    return Key(ROD, unit, allowed)


_MOTION_LAW = Key(
    TABLE,
    "",
    "`{ law = ..., <its parameters> }`",
    {
        "law": Key(STRING, "", '`"constant"`, `"linear"`, `"harmonic"`, `"spin_up"`'),
        "value": Key(NUMBER, "m or rad", "finite (constant, linear)"),
        "rate": Key(NUMBER, "per s", "finite (linear, spin_up)"),
        "amplitude": Key(NUMBER, "m or rad", "finite (harmonic)"),
        "omega": Key(NUMBER, "rad/s", "> 0, finite (harmonic)"),
        "phase": Key(NUMBER, "rad", "finite (harmonic)"),
        "time": Key(NUMBER, "s", "> 0, finite (spin_up)"),
    },
)

#: Every key of a scene file (``docs/scene_file.md``), by table.
SCENE_KEYS: dict[str, Key] = {
    "based_on": Key(STRING, "", '`"paper"`, or (in a file) the path of a scene file'),
    "name": Key(STRING),
    "n": Key(INTEGER, "", ">= 1 (memory permitting)"),
    "t_end": Key(NUMBER, "s", "> 0, finite"),
    "times": Key(
        TIMES,
        "s",
        "increasing, in [0, t_end]",
        {
            "start": Key(NUMBER, "s", ">= 0"),
            "stop": Key(NUMBER, "s", "<= t_end"),
            "num": Key(INTEGER, "", "[1, 1e6]"),
        },
    ),
    "outputs": Key(STRINGS, "", "quantities of `docs/quantities.md`"),
    "base": Key(
        TABLE,
        "",
        "",
        {
            "kind": Key(STRING, "", '`"pinned"`, `"free"`, `"prescribed"`'),
            "mass": Key(NUMBER, "kg", "> 0, <= 1e12 (free)"),
            "inertia": Key(NUMBER, "kg m^2", "> 0, <= 1e12 (free)"),
            "hinge_offset": Key(PAIR, "m", "finite"),
            "position": Key(PAIR, "m", "finite (free)"),
            "velocity": Key(PAIR, "m/s", "finite (free)"),
            "attitude": Key(NUMBER, "rad", "finite (free)"),
            "rate": Key(NUMBER, "rad/s", "finite (free)"),
            "motion": Key(
                TABLE,
                "",
                "prescribed only",
                {axis: _MOTION_LAW for axis in ("x", "y", "attitude")},
                section=True,
            ),
        },
        section=True,
        variant=("kind", "pinned"),
    ),
    "chain": Key(
        TABLE,
        "",
        "",
        {
            "l": _rod("m", "> 0"),
            "m": _rod("kg/m", "> 0"),
            "EI": _rod("N m^2", "> 0"),
            "mu": _rod("kg", ">= 0"),
            "kappa": _rod("N m/rad", ">= 0"),
            "nu": _rod("N m s/rad", ">= 0"),
            "rest_angle": _rod("rad", "finite"),
            "bending_damping": Key(
                ROD,
                "N m^2 s",
                ">= 0; or `{ ratio = ..., of = ... }`",
                {
                    "ratio": Key(
                        NUMBER_OR_NUMBERS, "", '>= 0 and < 1 (one per rod: `of = "panel"` only)'
                    ),
                    "of": Key(STRING, "", '`"panel"` (default), `"deployed"`'),
                },
            ),
        },
        section=True,
    ),
    "initial": Key(
        TABLE,
        "",
        "",
        {
            k: _rod("rad" if k in ("phi", "alpha", "beta") else "rad/s", "finite")
            for k in ("phi", "dphi", "alpha", "beta", "dalpha", "dbeta")
        },
        section=True,
    ),
    "loads": Key(
        TABLES,
        "",
        "",
        {
            "type": Key(
                STRING, "", "`pulse`, `constant`, `ramp`, `harmonic`, `tabulated`", required=True
            ),
            # required, but checked after the load's type (``scene_file._load``): the type says
            # which keys a load takes, so a bad type is named first
            "node": Key(NODE, "", '1..n, or `"last"`; required'),
            "Xbar": Key(NUMBER, "N", "finite (pulse)"),
            "Ybar": Key(NUMBER, "N", "finite (pulse)"),
            "T": Key(NUMBER, "s", "> 0 (pulse)"),
            "X": Key(NUMBER_OR_NUMBERS, "N", "finite (tabulated: one per time)"),
            "Y": Key(NUMBER_OR_NUMBERS, "N", "finite (tabulated: one per time)"),
            "t_on": Key(NUMBER, "s", ">= 0"),
            "t_full": Key(NUMBER, "s", ">= t_on (ramp)"),
            "t_off": Key(NUMBER, "s", "> t_on, may be inf"),
            "omega": Key(NUMBER, "rad/s", "> 0 (harmonic)"),
            "phase": Key(NUMBER, "rad", "finite (harmonic)"),
            "t": Key(NUMBERS, "s", "increasing, >= 0 (tabulated)"),
            "file": Key(STRING, "", "a CSV file with columns t, X and/or Y (tabulated)"),
        },
    ),
    # each hinge item declares its keys (rodval.core.hinges.HINGE_ITEMS)
    **{table: Key(TABLES, keys=item.KEYS) for table, item in HINGE_ITEMS.items()},
}


def _got(value: Any) -> str:
    return f"{type(value).__name__} {value!r:.60}"


def check_types(doc: Any, where: str) -> None:
    """ValueError "<where> key '<dotted path>': must be <type>, got <type> <value>" for the
    first value of the scene document ``doc`` whose type is not its key's (``SCENE_KEYS``),
    at every depth (an element of an array of tables by its index: ``latches.0.angle``).
    Unknown keys are left to the tables' own key checks."""
    if not isinstance(doc, dict):
        raise ValueError(f"{where}: a scene must be a table, got {_got(doc)}")
    _check_table(doc, SCENE_KEYS, "", where)


def _check_table(table: dict[str, Any], keys: dict[str, Key], prefix: str, where: str) -> None:
    for name, value in table.items():
        key = keys.get(name)
        if key is None:
            continue
        path = f"{prefix}{name}"
        if value is None and key.none:
            continue
        if not key.kind.accepts(value):
            within = f" ({key.allowed})" if key.allowed else ""
            raise ValueError(
                f"{where} key '{path}': must be {key.kind.words}{within}, got {_got(value)}"
            )
        if key.kind is TABLES:
            for i, item in enumerate(value):
                if not isinstance(item, dict):
                    raise ValueError(
                        f"{where} key '{path}.{i}': must be a table ([[{path}]]), got {_got(item)}"
                    )
                _check_table(item, key.keys, f"{path}.{i}.", where)
                missing = [k for k, sub in key.keys.items() if sub.required and k not in item]
                if missing:
                    raise missing_key(where, f"{path}.{i}.{missing[0]}")
        elif isinstance(value, dict) and key.keys:
            _check_table(value, key.keys, f"{path}.", where)


def key_at(path: str) -> Key:
    """The ``Key`` of the dotted scene ``path`` (an element of an array of tables by its
    index or ``*``: ``latches.0.hinge``); KeyError when ``SCENE_KEYS`` has no such key."""
    head, *rest = path.split(".")
    key = SCENE_KEYS[head]
    for part in rest:
        if key.kind is not TABLES or not (part == "*" or part.isdigit()):
            key = key.keys[part]
    return key


def missing_key(where: str, path: str) -> ValueError:
    """The one-line error of the required key at the dotted scene ``path`` that a table of the
    document ``where`` omits, with its type and range: "<where> key '<path>': is missing
    (<type>: <allowed>)"."""
    key = key_at(path)
    within = f": {key.allowed.replace('`', '')}" if key.allowed else ""
    return ValueError(f"{where} key '{path}': is missing ({key.kind.words}{within})")


# ------------------------------------------------------------------ paths and merging


def scene_path(key: str) -> str | None:
    """The dotted scene path a ``--set`` key names (``chain.EI``, or as a study's grid spells
    it, ``scene.chain.EI``), or None when the key is not a scene key (a model option)."""
    path = key.removeprefix("scene.")
    return path if path.split(".")[0] in SCENE_KEYS else None


def set_path(doc: dict[str, Any], path: str, value: Any) -> None:
    """Set ``value`` at the dotted ``path`` of ``doc``, creating tables on the way; in a list
    a segment is an index or ``*`` (every element: every latch). ValueError when the path
    runs into a value that is neither a table nor a list."""
    _set_parts(doc, path.split("."), value, path)


def _set_parts(node: Any, parts: list[str], value: Any, path: str) -> None:
    """``set_path`` from ``node`` down the remaining segments ``parts`` of ``path``."""
    head, rest = parts[0], parts[1:]
    if isinstance(node, list):
        if head == "*":
            index = range(len(node))
        elif head.isdigit() and int(head) < len(node):
            index = range(int(head), int(head) + 1)
        else:
            raise ValueError(f"{path}: {head!r} is not '*' or an index of a list of {len(node)}")
        for i in index:
            if rest:
                _set_parts(node[i], rest, value, path)
            else:
                node[i] = value
        return
    if not isinstance(node, dict):
        raise ValueError(f"{path}: {head!r} goes into {node!r:.40}, which is not a table or list")
    if not rest:
        node[head] = value
        return
    if node.get(head) is None:
        node[head] = {}
    _set_parts(node[head], rest, value, path)


def merge_documents(
    earlier: dict[str, Any], later: dict[str, Any], keys: dict[str, Key] = SCENE_KEYS
) -> dict[str, Any]:
    """``later`` laid over ``earlier`` (two scene documents): the sections (``Key.section``:
    [chain], [initial], [base], [base.motion]) merge key by key, at every depth, except a
    later section of another variant (``Key.variant``: a [base] of another ``kind``), which
    replaces the earlier one whole, as a pinned, free or prescribed base is described by
    keys of its own; any other value of ``later`` replaces ``earlier``'s whole. Neither
    argument is changed."""
    merged = {**earlier, **later}
    for name, key in keys.items():
        a, b = earlier.get(name), later.get(name)
        if key.section and isinstance(a, dict) and isinstance(b, dict):
            if not _other_variant(key, a, b):
                merged[name] = merge_documents(a, b, key.keys)
    return merged


def _other_variant(key: Key, earlier: dict[str, Any], later: dict[str, Any]) -> bool:
    """Whether the ``later`` table names another variant of ``key`` than ``earlier`` (its
    variant key given, with another value than the earlier table's or its default)."""
    if key.variant is None:
        return False
    name, default = key.variant
    return name in later and later[name] != earlier.get(name, default)


# ------------------------------------------------------------------ the table in the docs

#: The markers around the generated table in docs/scene_file.md.
DOC_BEGIN = "<!-- key table: generated by python -m rodval.core.scene_keys --write -->"
DOC_END = "<!-- end of key table -->"


def _rows(keys: dict[str, Key], prefix: str) -> list[str]:
    """The table's rows of ``keys`` under ``prefix``, depth first; the three motion axes share
    one set of rows (``base.motion.AXIS``)."""
    rows = []
    for name, key in keys.items():
        path = f"{prefix}{name}"
        if path in ("base.motion.y", "base.motion.attitude"):
            continue
        shown = f"`{path}`".replace("base.motion.x", "base.motion.AXIS")
        if path == "base.motion.x":
            shown = "`base.motion.AXIS` (AXIS: `x`, `y`, `attitude`)"
        notes = [key.allowed] if key.allowed else []
        notes += ["required"] * key.required
        rows.append(f"| {shown} | {key.kind.words} | {key.unit} | {'; '.join(notes)} |")
        rows += _rows(key.keys, f"{path}.*." if key.kind is TABLES else f"{path}.")
    return rows


def doc_table() -> str:
    """The key table of docs/scene_file.md (markdown, between ``DOC_BEGIN`` and ``DOC_END``)."""
    lines = [
        DOC_BEGIN,
        "| key | type | unit | allowed |",
        "|---|---|---|---|",
        *_rows(SCENE_KEYS, ""),
        DOC_END,
    ]
    return "\n".join(lines)


def with_doc_table(text: str) -> str:
    """``text`` (docs/scene_file.md) with its key table replaced by ``doc_table()``;
    ValueError when the markers are missing."""
    pattern = re.compile(re.escape(DOC_BEGIN) + ".*?" + re.escape(DOC_END), re.S)
    if not pattern.search(text):
        raise ValueError(f"the key table's markers ({DOC_BEGIN!r} ... {DOC_END!r}) are missing")
    return pattern.sub(lambda _: doc_table(), text, count=1)


def main(argv: list[str] | None = None) -> int:
    """``--doc-table``: print the key table; ``--write FILE``: replace it in FILE."""
    p = argparse.ArgumentParser(prog="python -m rodval.core.scene_keys", description=__doc__)
    p.add_argument("--doc-table", action="store_true", help="print the key table")
    p.add_argument("--write", type=Path, metavar="FILE", help="replace the key table in FILE")
    args = p.parse_args(argv)
    if args.write is not None:
        args.write.write_text(with_doc_table(args.write.read_text()))
    if args.doc_table or args.write is None:
        print(doc_table())
    return 0


if __name__ == "__main__":
    sys.exit(main())

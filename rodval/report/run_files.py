"""The output folder of one run (``rodval simulate``).

Files:

* ``run.json``: the complete resolved scene, model, options, integrator settings as used, how
  the run ended, its events and provenance, the files the run wrote (``files``) and the size
  and SHA-256 of its trajectory table and of ``scene_arrays.npz``. It carries rodval's stamp
  (``rodval.core.out_paths.stamp``, schema ``RUN_SCHEMA``): a folder is a run folder of rodval
  only while its run.json is stamped, and only such a folder (or a new or empty one) is
  written into (``claim_run_folder``). Reading a run.json as an input (a rerun, ``compare``,
  ``animate``, ``modes``) does not ask for the stamp: an edited run.json is the user's request.
* the trajectory: ``trajectory.csv`` (tidy t, quantity, k, value), or for a large run
  (``table="auto"``, more than ``CSV_MAX_VALUES`` values) ``trajectory.npz`` (the times, each
  quantity's values and k labels as float64 / int64 arrays: written in a fraction of the
  time of the text table);
  A bending damping stated as a ratio is recorded under ``bending_damping`` (the request and,
  for the deployed structure, its conversion: ``DAMPING_KEY``) beside the scene's c;
* ``trajectory_wide.csv`` on request (one row per output time);
* ``scene_arrays.npz`` when the scene has lists of more than ``INLINE_MAX`` numbers (a large
  chain's per-rod fields and initial state): run.json then holds, in their place,
  ``{"stored_in": "scene_arrays.npz", "key": <dotted path>}``; ``read_run_record`` puts the
  arrays back (bit for bit), after checking the file's recorded digest.

``read_run`` is the inverse of ``write_run``: a run folder is enough to compare runs or to
rerun one exactly. It refuses a trajectory table that is not the one its run wrote (cut short,
edited, damaged) or whose digest run.json does not record, naming the file and what is wrong.
A new run into a run folder removes the files the previous run wrote that it does not write
itself (a ``trajectory_wide.csv`` of another n), and nothing else. A run folder that is or holds
a symbolic link (a run.json linked to another run's) is refused before any work, and every file
is written through ``rodval.core.out_paths.write_file`` (never through a link).
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import json
import time
import zipfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from rodval.core.checks import check_keys
from rodval.core.out_paths import (
    CHECKSUM_KEY,
    RUN_SCHEMA,
    SCHEMA_KEY,
    is_stamped,
    read_json,
    refuse_foreign,
    stamp,
    write_file,
)
from rodval.core.provenance import provenance
from rodval.core.scene import Scene
from rodval.core.scene_file import scene_to_dict
from rodval.core.trajectory import SolverStats, Trajectory, result_fields
from rodval.models.observation.deployed_damping import resolve_damping

RUN_JSON = "run.json"
TABLE_CSV, TABLE_NPZ = "trajectory.csv", "trajectory.npz"
WIDE_CSV, ARRAYS_NPZ = "trajectory_wide.csv", "scene_arrays.npz"
#: Every file a run may write besides run.json: the only names a new run removes (those the
#: previous run's stamped run.json lists and the new run does not write).
RUN_FILES = (TABLE_CSV, TABLE_NPZ, WIDE_CSV, ARRAYS_NPZ)

RUN_KEYS = ("scene", "model", "options", "settings", "stats")
#: The type of each of them (a run.json whose keys have other types is refused).
RUN_KEY_TYPES = {"scene": dict, "model": str, "options": dict, "settings": dict, "stats": dict}
#: run.json's record of its trajectory table: {"bytes": size, "sha256": hex digest}.
DIGEST_KEY = "trajectory_csv"
NPZ_DIGEST_KEY = "trajectory_npz"
#: run.json's record of scene_arrays.npz: {"bytes", "sha256"}.
ARRAYS_KEY = "scene_arrays"
#: run.json's list of the files its run wrote (besides run.json).
FILES_KEY = "files"
#: run.json's record of a bending damping stated as a ratio (``rodval.core.damping``): the
#: request ``ratio``, ``of`` and, for the deployed structure, its conversion (``c_N_m2_s``
#: per rod, ``beta_s``, the mode's ``mode_omega_rad_s`` and ``zeta``, ``iterations``,
#: ``model``); the scene holds the c that ran.
DAMPING_KEY = "bending_damping"
#: The keys a run.json may hold besides ``RUN_KEYS``.
OPTIONAL_KEYS = (
    "events",
    "provenance",
    DIGEST_KEY,
    NPZ_DIGEST_KEY,
    ARRAYS_KEY,
    FILES_KEY,
    DAMPING_KEY,
    SCHEMA_KEY,
    CHECKSUM_KEY,
)
#: Lists of the scene longer than this (entries) go to scene_arrays.npz.
INLINE_MAX = 1000
#: Trajectory formats: "csv" (tidy text), "npz" (binary), "auto" (csv up to CSV_MAX_VALUES).
TABLE_FORMATS = ("auto", "csv", "npz")
#: Largest trajectory (values) "auto" writes as trajectory.csv (~20 MB of text).
CSV_MAX_VALUES = 1_000_000
#: The reference that stands in run.json for an array kept in scene_arrays.npz.
STORED_IN = "stored_in"
#: Rows of the tidy table formatted at once (bounds the writer's memory to ~25 MB).
_CHUNK_ROWS = 1 << 18
#: Values of the writers' timing sample (``write_estimate_s``).
SAMPLE_VALUES = 20_000
#: Per-rod arrays of a scene (8 chain fields, 6 of the initial state).
SCENE_ARRAYS = 14
#: What ``write_estimate_s`` adds to the writers' sampled cost (the disk, run.json).
ESTIMATE_FACTOR = 1.5
#: Longest shortest-round-trip text of a float64 ("-1.2345678901234567e-308": 24 bytes).
_FLOAT_WIDTH = 25


def file_digest(data: bytes) -> dict[str, Any]:
    """Size (bytes) and SHA-256 (hex) of a file's content, as run.json records them."""
    return {"bytes": len(data), "sha256": hashlib.sha256(data).hexdigest()}


def check_digest(path: Path, recorded: Any, key: str = DIGEST_KEY) -> None:
    """ValueError naming ``path`` unless its content has the size and SHA-256 ``recorded``
    (run.json's ``key``)."""
    check_keys(recorded, ("bytes", "sha256"), f"run.json key {key!r}")
    have = file_digest(path.read_bytes())
    if have["bytes"] != recorded.get("bytes"):
        raise ValueError(
            f"{path}: damaged: {have['bytes']} bytes, but run.json records "
            f"{recorded.get('bytes')} (the file was cut short or changed)"
        )
    if have["sha256"] != recorded.get("sha256"):
        raise ValueError(
            f"{path}: damaged: its SHA-256 differs from the one run.json records "
            "(the file was edited or damaged)"
        )


# ------------------------------------------------------------------ ownership of a folder


def owns_run_folder(folder: Path) -> bool:
    """Whether ``folder`` is a run folder of rodval: its run.json carries rodval's stamp."""
    return is_stamped(read_json(folder / RUN_JSON), RUN_SCHEMA)


def claim_run_folder(out: Path, flag: str = "--out") -> None:
    """ValueError naming ``flag`` unless ``out`` is missing, empty or a run folder of rodval
    (``owns_run_folder``), before any work: rodval overwrites none of the user's files. An
    unstamped run.json (edited, or written by an older rodval) is named as such."""
    try:
        refuse_foreign(out, flag, owns_run_folder, "run", RUN_JSON)
    except ValueError as exc:
        if not (out / RUN_JSON).is_file():
            raise
        raise ValueError(
            f"{exc} (its run.json was edited or written by an older rodval, so it is no "
            f"longer rodval's record; it still reruns as SCENE: rodval simulate "
            f"{out / RUN_JSON} --out NEW, with a new folder)"
        ) from None
    if out.is_dir():  # a run folder: a file named like a run's that its run did not write
        listed = _previous_files(out)
        foreign = [n for n in RUN_FILES if (out / n).exists() and n not in listed]
        if foreign:
            raise ValueError(
                f"{flag} {out}: holds {', '.join(map(repr, foreign))}, which its run.json "
                "does not list among the files rodval wrote, so rodval will not write there; "
                "use a new or empty folder"
            )


def _previous_files(out: Path) -> list[str]:
    """The files (``RUN_FILES`` names) the run whose stamped run.json is in ``out`` wrote."""
    record = read_json(out / RUN_JSON)
    if not is_stamped(record, RUN_SCHEMA):
        return []
    files = record.get(FILES_KEY, [])
    return [f for f in files if f in RUN_FILES] if isinstance(files, list) else []


# ------------------------------------------------------------------------ the tidy table


def _float_bytes(a: np.ndarray) -> np.ndarray:
    """float64 values as fixed-width bytes, each the shortest text that reads back as the
    same float (Python's ``repr``, as pandas writes it), NaN as empty (pandas' ``na_rep``)."""
    text = np.asarray(a, dtype=np.float64).astype(f"S{_FLOAT_WIDTH}")
    text[np.isnan(a)] = b""
    return text


def _as_matrix(text: np.ndarray) -> np.ndarray:
    """A fixed-width bytes array (m,) as its (m, width) uint8 matrix (NUL padded)."""
    width = text.dtype.itemsize
    return np.ascontiguousarray(text).view(np.uint8).reshape(text.size, width)


def _tidy_rows(t: np.ndarray, quantity: str, k: np.ndarray, values: np.ndarray) -> Iterator[bytes]:
    """The tidy rows ``t,quantity,k,value`` of one quantity (values (nt, nk)), in chunks:
    each row's fields laid in a byte matrix, the NUL padding dropped (vectorised)."""
    nt, nk = values.shape
    if nt * nk == 0:
        return
    tt, kk = _as_matrix(_float_bytes(t)), _as_matrix(k.astype(np.int64).astype("S21"))
    name = np.frombuffer(f",{quantity},".encode(), np.uint8)
    flat = values.reshape(-1)
    widths = (tt.shape[1], name.size, kk.shape[1], 1, _FLOAT_WIDTH, 1)
    edges = np.cumsum((0, *widths))
    for start in range(0, nt * nk, _CHUNK_ROWS):
        rows = np.arange(start, min(start + _CHUNK_ROWS, nt * nk))
        block = np.zeros((rows.size, int(edges[-1])), np.uint8)
        block[:, edges[0] : edges[1]] = tt[rows // nk]
        block[:, edges[1] : edges[2]] = name
        block[:, edges[2] : edges[3]] = kk[rows % nk]
        block[:, edges[3]] = ord(",")
        block[:, edges[4] : edges[5]] = _as_matrix(_float_bytes(flat[rows]))
        block[:, edges[5]] = ord("\n")
        yield block[block != 0].tobytes()


def tidy_csv(traj: Trajectory) -> bytes:
    """trajectory.csv's bytes: the tidy table ``traj.to_frame()`` (columns t, quantity, k,
    value), byte for byte as pandas' ``to_csv(index=False)`` writes it, formatted with numpy
    (each time and k label once, not once per row)."""
    parts = [b"t,quantity,k,value\n"]
    for q, arr in traj.values.items():
        parts += _tidy_rows(traj.times, q, np.asarray(traj.k_index[q]), np.asarray(arr, float))
    return b"".join(parts)


def trajectory_npz(traj: Trajectory) -> bytes:
    """trajectory.npz's bytes: ``t`` (s), ``quantities`` (names in order) and per quantity q
    ``values:q`` (nt, nk) float64 and ``k:q`` int64 (units: ``rodval.core.scene.UNITS``)."""
    arrays: dict[str, np.ndarray] = {
        "t": np.asarray(traj.times, np.float64),
        "quantities": np.array(list(traj.values), dtype=str),
    }
    for q, arr in traj.values.items():
        arrays[f"values:{q}"] = np.asarray(arr, np.float64)
        arrays[f"k:{q}"] = np.asarray(traj.k_index[q], np.int64)
    return _npz_bytes(arrays)


def value_count(traj: Trajectory) -> int:
    """The number of values (rows of the tidy table) of ``traj``."""
    return int(sum(np.size(v) for v in traj.values.values()))


def write_estimate_s(values: int, table: str, rods: int, *, wide: bool = False) -> float:
    """Estimated seconds to write a run folder: ``values`` trajectory values into ``table``
    (``TABLE_CSV`` or ``TABLE_NPZ``; with ``wide`` once more as text) and, for a chain of more
    than ``INLINE_MAX`` ``rods``, its per-rod arrays (``SCENE_ARRAYS`` of them: listed for
    ``scene_to_dict``, then packed into scene_arrays.npz). Each writer is timed on a sample of
    at most ``SAMPLE_VALUES`` values on this machine, now, scaled linearly (their cost is
    linear in the values) and by ``ESTIMATE_FACTOR`` for what the sample leaves out (the
    disk, the rest of run.json)."""
    m = max(1, min(max(values, rods), SAMPLE_VALUES) // 2)
    sample = np.random.default_rng(0).standard_normal((2, m)) * 10.0
    t, k = np.array([0.5, 1.0]), np.arange(1, m + 1)

    def per_value(write: Callable[[], object]) -> float:
        begin = time.perf_counter()
        write()
        return (time.perf_counter() - begin) / sample.size

    text_s = per_value(lambda: b"".join(_tidy_rows(t, "phi", k, sample)))
    binary_s = per_value(lambda: file_digest(_npz_bytes({"values": sample})))
    listed_s = per_value(sample.tolist)
    total = values * (text_s if table == TABLE_CSV else binary_s)
    if wide:
        total += values * text_s
    if rods > INLINE_MAX:
        total += SCENE_ARRAYS * rods * (binary_s + listed_s)
    return ESTIMATE_FACTOR * total


def table_file(fmt: str, values: int) -> str:
    """The trajectory file of a run of ``values`` values in format ``fmt`` (``TABLE_FORMATS``)."""
    if fmt not in TABLE_FORMATS:
        raise ValueError(f"table format must be one of {TABLE_FORMATS}, got {fmt!r}")
    if fmt == "npz" or (fmt == "auto" and values > CSV_MAX_VALUES):
        return TABLE_NPZ
    return TABLE_CSV


# ----------------------------------------------------------------- large scene arrays


def _homogeneous_numbers(value: Any) -> bool:
    """Whether ``value`` is a list of floats only or of ints only (no bools): an array that
    round-trips through npz with its JSON types."""
    if not isinstance(value, list) or not value:
        return False
    kinds = set(map(type, value))
    return kinds == {float} or kinds == {int}


def split_arrays(
    doc: Any, path: str = "", known: dict[str, np.ndarray] | None = None
) -> tuple[Any, dict[str, np.ndarray]]:
    """``doc`` (a scene dict) with every list of more than ``INLINE_MAX`` numbers replaced by
    ``{"stored_in": "scene_arrays.npz", "key": <dotted path>}``, and those arrays by key.
    ``known``: float64 arrays by dotted path whose ``tolist()`` the lists there are (the
    scene's own arrays: taken as they are, not converted back from the list)."""
    known = known or {}
    if isinstance(doc, dict):
        out, arrays = {}, {}
        for k, v in doc.items():
            out[k], more = split_arrays(v, f"{path}.{k}" if path else str(k), known)
            arrays.update(more)
        return out, arrays
    if isinstance(doc, list):
        if len(doc) > INLINE_MAX:
            array = known.get(path)
            if (
                array is not None
                and array.dtype == np.float64
                and array.shape == (len(doc),)
                and doc[0] == array[0]
                and doc[-1] == array[-1]
            ):
                return {STORED_IN: ARRAYS_NPZ, "key": path}, {path: array}
            if _homogeneous_numbers(doc):
                dtype = np.float64 if isinstance(doc[0], float) else np.int64
                return {STORED_IN: ARRAYS_NPZ, "key": path}, {path: np.array(doc, dtype=dtype)}
        pairs = [split_arrays(v, f"{path}.{i}", known) for i, v in enumerate(doc)]
        arrays = {}
        for _, more in pairs:
            arrays.update(more)
        return [p for p, _ in pairs], arrays
    return doc, {}


def scene_record(scene: Scene) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """run.json's scene (``scene_to_dict``, its large lists replaced by references) and the
    arrays for scene_arrays.npz: the chain's fields, the initial state and the output times
    taken from the scene itself (``scene_to_dict`` lists exactly these), any other large
    list converted."""
    known = {"times": np.asarray(scene.times)}
    known.update({f"chain.{f}": getattr(scene.chain, f) for f in scene.chain.FIELDS})
    known.update({f"initial.{k}": v for k, v in scene.initial.resolve(scene.n).items()})
    doc, arrays = split_arrays(scene_to_dict(scene), known=known)
    return doc, arrays


def _is_reference(value: Any) -> bool:
    return isinstance(value, dict) and STORED_IN in value


def _references(doc: Any) -> bool:
    if _is_reference(doc):
        return True
    if isinstance(doc, dict):
        return any(_references(v) for v in doc.values())
    if isinstance(doc, list):
        return any(_references(v) for v in doc)
    return False


def join_arrays(doc: Any, arrays: Any, where: str) -> Any:
    """Inverse of ``split_arrays``: every reference replaced by its array as a list (the
    JSON types: float or int). ValueError naming ``where`` for a reference to no array."""
    if _is_reference(doc):
        check_keys(doc, (STORED_IN, "key"), f"{where}: array reference")
        key = doc.get("key")
        if doc[STORED_IN] != ARRAYS_NPZ or not isinstance(key, str) or key not in arrays:
            raise ValueError(
                f"{where}: the array reference {doc!r:.80} names no array of {ARRAYS_NPZ}"
            )
        return arrays[key].tolist()
    if isinstance(doc, dict):
        return {k: join_arrays(v, arrays, where) for k, v in doc.items()}
    if isinstance(doc, list):
        return [join_arrays(v, arrays, where) for v in doc]
    return doc


def _npz_bytes(arrays: dict[str, np.ndarray]) -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, allow_pickle=False, **arrays)
    return buffer.getvalue()


def _load_npz(path: Path) -> Any:
    """The arrays of an npz file (no pickles), ValueError naming it when it is not one."""
    try:
        return np.load(path, allow_pickle=False)
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        raise ValueError(f"{path}: damaged or not an npz file of rodval ({exc})") from None


def _scene_arrays(path: Path, rec: dict[str, Any]) -> dict[str, np.ndarray]:
    """The arrays of the run's scene_arrays.npz beside run.json ``path``, its digest checked."""
    npz = path.parent / ARRAYS_NPZ
    if ARRAYS_KEY not in rec:
        raise ValueError(
            f"{path}: its scene names arrays of {ARRAYS_NPZ} but records no digest of it "
            f"(key {ARRAYS_KEY!r})"
        )
    if not npz.is_file():
        raise ValueError(
            f"{npz} does not exist (run.json keeps its scene's large arrays there: copy it "
            "together with run.json)"
        )
    check_digest(npz, rec[ARRAYS_KEY], ARRAYS_KEY)
    with _load_npz(npz) as data:
        return {k: data[k] for k in data.files}


# ---------------------------------------------------------------------------- writing


def write_run(
    traj: Trajectory,
    scene: Scene,
    out: Path,
    *,
    wide: bool = False,
    table: str = "auto",
    claimed: bool = False,
) -> list[str]:
    """Write the run folder ``out``: the trajectory (``table``: "csv" trajectory.csv, "npz"
    trajectory.npz, "auto" the csv up to ``CSV_MAX_VALUES`` values), trajectory_wide.csv when
    ``wide``, scene_arrays.npz when the scene has large arrays, and the stamped run.json
    (written last) that records their digests and names. The files of the previous run in
    ``out`` that this run does not write are removed first. ValueError (before writing) when
    ``out`` holds files rodval did not write, unless ``claimed`` (the caller's
    ``claim_run_folder`` before the run). Returns the files written besides run.json."""
    out = Path(out)
    if not claimed:
        claim_run_folder(out)
    scene = resolve_damping(scene)  # the c the models ran (converted once per process)
    doc, arrays = scene_record(scene)
    name = table_file(table, value_count(traj))
    files = [name, *([WIDE_CSV] if wide else []), *([ARRAYS_NPZ] if arrays else [])]
    out.mkdir(parents=True, exist_ok=True)
    for stale in set(_previous_files(out)) - set(files):
        (out / stale).unlink(missing_ok=True)
    data = tidy_csv(traj) if name == TABLE_CSV else trajectory_npz(traj)
    write_file(out / name, data)
    record: dict[str, Any] = {
        "scene": doc,
        **traj.result_dict(),  # the same fields as a case record's (model ... events)
        "provenance": provenance(),
        DIGEST_KEY if name == TABLE_CSV else NPZ_DIGEST_KEY: file_digest(data),
        FILES_KEY: files,
    }
    if scene.damping is not None:
        record[DAMPING_KEY] = scene.damping.record()
    if wide:
        write_file(out / WIDE_CSV, traj.to_frame(wide=True).to_csv(index=False))
    if arrays:
        packed = _npz_bytes(arrays)
        write_file(out / ARRAYS_NPZ, packed)
        record[ARRAYS_KEY] = file_digest(packed)
    # a round trip through JSON first, so that the stamp is the checksum of what is read back
    plain = json.loads(json.dumps(record, default=str))
    write_file(out / RUN_JSON, json.dumps(stamp(plain, RUN_SCHEMA), indent=2))
    return files


# ---------------------------------------------------------------------------- reading


def check_events(events: Any, path: Path) -> None:
    """ValueError naming ``path`` and the event unless ``events`` (run.json's key) is a list
    of tables, each with a text ``label`` and a finite time ``t`` (s): rodval records every
    event at the time it happened, so a blank, NaN or infinite time is an edited or damaged
    record (compared, it would be a blank cell of events.csv with no reason)."""
    if not isinstance(events, list) or not all(isinstance(e, dict) for e in events):
        raise ValueError(f"{path}: key 'events' must be a list of tables, got {events!r:.60}")
    for i, ev in enumerate(events):
        t, label = ev.get("t"), ev.get("label")
        if not isinstance(label, str):
            raise ValueError(f"{path}: key 'events' item {i}: 'label' must be text, got {label!r}")
        if isinstance(t, bool) or not isinstance(t, int | float) or not np.isfinite(t):
            raise ValueError(
                f"{path}: key 'events' item {i} ({label!r}): its time 't' must be a finite "
                f"number (s), got {t!r} (rodval records every event at the time it happened: "
                "the record was edited or damaged)"
            )


def read_run_record(path: Path) -> dict[str, Any]:
    """The run.json at ``path`` (ValueError naming the file when it is not one), its scene's
    arrays kept in scene_arrays.npz put back. Its stamp is not required: an edited run.json
    is a request like a scene file."""
    if not path.is_file():
        raise ValueError(f"{path} does not exist")
    try:
        rec = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: damaged or not a run.json (not valid JSON: {exc})") from None
    missing = [k for k in RUN_KEYS if not isinstance(rec, dict) or k not in rec]
    if missing:
        raise ValueError(f"{path}: not a run.json of rodval simulate (no {missing[0]!r})")
    check_keys(rec, (*RUN_KEYS, *OPTIONAL_KEYS), str(path))
    for key, kind in RUN_KEY_TYPES.items():
        if not isinstance(rec[key], kind):
            raise ValueError(
                f"{path}: key {key!r} must be a {'table' if kind is dict else 'string'}, "
                f"got {rec[key]!r:.60}"
            )
    check_events(rec.get("events", []), path)
    files = rec.get(FILES_KEY, [])
    if not isinstance(files, list) or not all(isinstance(f, str) for f in files):
        raise ValueError(
            f"{path}: key {FILES_KEY!r} must be a list of file names, got {files!r:.60}"
        )
    if _references(rec["scene"]):
        rec["scene"] = join_arrays(rec["scene"], _scene_arrays(path, rec), str(path))
    record: dict[str, Any] = rec
    return record


def _no_digest(folder: Path) -> ValueError:
    return ValueError(
        f"{folder / TABLE_CSV}: run.json records no digest of {TABLE_CSV} (written before "
        "rodval recorded one, or edited), so its completeness cannot be checked; rerun it: "
        f"rodval simulate {folder / RUN_JSON} --out NEW"
    )


def _read_csv(path: Path, rec: dict[str, Any]) -> Trajectory:
    import pandas as pd

    try:
        frame = pd.read_csv(path)
        return Trajectory.from_frame(frame, rec["model"], rec["scene"].get("name", "scene"))
    except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError, KeyError, ValueError) as exc:
        raise ValueError(f"{path}: not a trajectory table of rodval simulate ({exc})") from None


def _read_npz(path: Path, rec: dict[str, Any]) -> Trajectory:
    with _load_npz(path) as data:
        try:
            times = np.asarray(data["t"], np.float64)
            values, k_index = {}, {}
            for q in data["quantities"].tolist():
                values[q] = np.asarray(data[f"values:{q}"], np.float64)
                k_index[q] = np.asarray(data[f"k:{q}"], np.int64)
                if values[q].shape != (times.size, k_index[q].size):
                    raise ValueError(f"values of {q!r} are not (times, k labels)")
        except (KeyError, ValueError, TypeError) as exc:
            raise ValueError(f"{path}: not a trajectory of rodval simulate ({exc})") from None
    name = rec["scene"].get("name", "scene")
    return Trajectory(rec["model"], name, times, values, k_index, SolverStats())


def read_run(folder: Path) -> Trajectory:
    """The trajectory of a run folder written by ``write_run``, with its stats, settings,
    options and events. ValueError naming the file when the trajectory table is not the one
    its run.json records, or when run.json records no digest of it (a table cut short could
    not be told from a shorter run)."""
    rec = read_run_record(folder / RUN_JSON)
    if NPZ_DIGEST_KEY in rec:
        path = folder / TABLE_NPZ
        if not path.is_file():
            raise ValueError(f"{path} does not exist")
        check_digest(path, rec[NPZ_DIGEST_KEY], NPZ_DIGEST_KEY)
        traj = _read_npz(path, rec)
    else:
        path = folder / TABLE_CSV
        if not path.is_file():
            raise ValueError(f"{path} does not exist")
        if DIGEST_KEY not in rec:
            raise _no_digest(folder)
        check_digest(path, rec[DIGEST_KEY])
        traj = _read_csv(path, rec)
    try:
        fields = result_fields(rec)
    except TypeError as exc:
        raise ValueError(f"{folder / RUN_JSON}: key 'stats': {exc}") from None
    return dataclasses.replace(traj, **fields)

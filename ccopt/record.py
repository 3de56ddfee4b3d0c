"""The run record of docs/architecture.md §8, written incrementally so an interrupted run keeps its data.

A run folder holds

``meta.json``
    object, parameters, seed, schedule, versions, the run's ``run_id`` and ``status``:
    ``running``, ``completed`` or ``interrupted`` (written first, updated on close);
``chunks/chunk_NNNNN.npz``
    the time series, a chunk every ``flush_every`` samples, each written atomically (through
    ``chunk_NNNNN.partial.npz``) and tagged with the ``run_id``;
``record.npz``
    all chunks concatenated, tagged with the ``run_id``, written atomically on close (the chunks are
    then removed);
``summary.json``
    the metrics, written on close.

A run writes only into a new or empty folder (:func:`prepare_folder`), so two runs are never mixed.
:func:`load_record` also checks it: it reads ``record.npz`` when that belongs to the run of
``meta.json`` (same ``run_id``), otherwise that run's chunks, and never a ``*.partial*`` file.
"""

from __future__ import annotations

import contextlib
import json
import os
import platform
import re
import uuid
import zipfile
import zlib
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

import numpy as np

CHUNKS = "chunks"
RUN_ID_KEY = "__run_id__"
"""Key of the ``run_id`` in every chunk and in ``record.npz`` (not a data key)."""
RUN_FILES = frozenset(
    {
        "meta.json", "summary.json", "record.npz", "feasibility_map.npz",  # the record
        "meta.partial", "summary.partial", "record.partial.npz", "feasibility_map.npz.partial",
        ".write_probe",  # files being written, the probe of a writable folder
        "estimation.png", "friction_cones.png", "control.png", "animation.gif",  # figures
        "feasibility_map.png",
    }
)  # fmt: skip
"""The files a run and its figures write in a run folder (besides the chunks), by name: what
``prepare_folder(..., overwrite=True)`` may remove. Any other file, a ``photo.png`` too, is the user's."""
_CHUNK = re.compile(r"chunk_(\d+)\.npz")
_CHUNK_FILE = re.compile(r"chunk_\d+(\.partial)?\.npz")


def prepare_folder(folder: str | Path, overwrite: bool = False) -> Path:
    """Make ``folder`` ready for a new run and return it: created if needed, and writable.

    The folder must be new or empty. With ``overwrite``, the files a run writes (:data:`RUN_FILES`,
    ``chunks/chunk_*.npz``) are removed first, and a folder holding anything else is refused.
    ``ValueError`` with one line naming the value or the file otherwise: an empty path, the current
    directory, a path that is not a folder, an unwritable folder. Nothing is created or
    removed when it raises.
    """
    text = os.fspath(folder)
    if "\0" in text:
        raise ValueError(f"output folder {text!r} is not a valid path (it holds a NUL character)")
    path = Path(text)
    try:
        if not text.strip() or path.resolve() == Path.cwd().resolve():
            raise ValueError(f"output folder {text!r} is the current directory; name a new or empty folder")
        if path.exists() and not path.is_dir():
            raise ValueError(f"output folder {text!r} exists and is not a folder")
        previous_run = _previous_run_files(path, overwrite) if path.is_dir() else []
        _create_writable(path)
        for entry in previous_run:
            entry.unlink(missing_ok=True)  # the probe has already replaced and removed .write_probe
        if (path / CHUNKS).is_dir():
            (path / CHUNKS).rmdir()
    except OSError as error:
        raise ValueError(f"cannot write to output folder {text!r}: {error.strerror or error}") from None
    return path


def _create_writable(path: Path) -> None:
    """Create ``path`` (and its parents) and write a probe file in it; ``OSError`` after removing
    the folders it created if that fails."""
    missing = missing_folders(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
        probe = path / ".write_probe"
        probe.write_text("")
        probe.unlink()
    except OSError:
        remove_empty_folders(missing)
        raise


def missing_folders(folder: str | Path) -> list[Path]:
    """``folder`` and its parents that do not exist (what :func:`prepare_folder` creates), deepest
    first."""
    path = Path(folder)
    return [p for p in (path, *path.parents) if not p.exists()]


def remove_empty_folders(folders: list[Path]) -> None:
    """Remove each of ``folders`` (deepest first) that exists and is empty; leave the others."""
    for folder in folders:
        with contextlib.suppress(OSError):  # gone, or not empty: not ours to remove
            folder.rmdir()


def discard_unstarted(folder: str | Path) -> bool:
    """Remove the files of a run that never began (it was stopped or failed while starting): no
    sample, and ``meta.json`` absent or still ``running``; its files are ``meta.json``, the empty
    chunks folder, a write probe. Returns whether nothing of the run is left (also when the folder
    does not exist); a folder holding samples, a run that ended, or anything a run does not write is
    left as it is."""
    path = Path(folder)
    if not path.is_dir():
        return True
    if (path / "record.npz").exists() or _chunk_files(path):
        return False
    if (path / "meta.json").exists():
        try:
            if _read_json_object(path / "meta.json").get("status") != "running":
                return False
        except ValueError:  # not a run's meta.json
            return False
    try:
        entries = _previous_run_files(path, overwrite=True)
    except ValueError:  # something not written by a run: not ours to remove
        return False
    for entry in entries:
        entry.unlink(missing_ok=True)
    with contextlib.suppress(OSError):  # absent, or not empty
        (path / CHUNKS).rmdir()
    return True


def _previous_run_files(path: Path, overwrite: bool) -> list[Path]:
    """The files of a previous run in the folder ``path``, to be removed (``overwrite``), chunks last;
    ``ValueError`` naming the folder if it is not empty and not ``overwrite``, or naming the first
    entry a run does not write."""
    entries = sorted(path.iterdir())
    if entries and not overwrite:
        raise ValueError(
            f"output folder {str(path)!r} is not empty (it holds {entries[0].name!r}); "
            "choose a new folder or overwrite it"
        )
    chunks = sorted((path / CHUNKS).iterdir()) if (path / CHUNKS).is_dir() else []
    files = [entry for entry in entries if entry.name != CHUNKS or not entry.is_dir()]
    foreign = [entry for entry in files if not (entry.is_file() and entry.name in RUN_FILES)]
    foreign += [chunk for chunk in chunks if not (chunk.is_file() and _CHUNK_FILE.fullmatch(chunk.name))]
    if foreign:
        raise ValueError(
            f"will not overwrite {str(path)!r}: {str(foreign[0])!r} was not written by a run; "
            "move it away or choose another folder"
        )
    return files + chunks


def versions() -> dict[str, str]:
    """Versions of Python and the libraries a run depends on."""
    found = {"python": platform.python_version()}
    for name in ("ccopt", "numpy", "casadi", "mujoco", "pin", "cvxpy", "clarabel"):
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = "absent"
    return found


def _write_json(path: Path, content: dict[str, object]) -> None:
    partial = path.with_suffix(".partial")
    partial.write_text(json.dumps(content, indent=2, sort_keys=True, default=_jsonable) + "\n")
    os.replace(partial, path)


def _jsonable(value: object) -> object:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"cannot store {type(value).__name__} in JSON")


def write_summary(folder: str | Path, summary: dict[str, object]) -> None:
    """Write (or replace) a run folder's ``summary.json``."""
    _write_json(Path(folder) / "summary.json", summary)


def _save_npz(target: Path, arrays: dict[str, np.ndarray], run_id: str, compressed: bool = False) -> None:
    """Write ``arrays`` tagged with ``run_id`` to ``target`` atomically (through ``*.partial.npz``)."""
    partial = target.with_suffix(".partial.npz")
    save = np.savez_compressed if compressed else np.savez
    save(partial, **arrays, **{RUN_ID_KEY: np.str_(run_id)})
    os.replace(partial, target)


class RecordWriter:
    """Appends samples (dicts of scalars/arrays with fixed keys and shapes) to a new run folder.

    Args:
        folder: the run folder, new or empty (:func:`prepare_folder`).
        meta: what ``meta.json`` records besides ``status``, ``versions`` and ``run_id``.
        flush_every: samples per chunk (≥ 1).
        overwrite: clear a previous run's files from ``folder`` first (:func:`prepare_folder`).
    """

    def __init__(
        self, folder: str | Path, meta: dict[str, object], flush_every: int = 500, overwrite: bool = False
    ) -> None:
        if isinstance(flush_every, bool) or not isinstance(flush_every, int) or flush_every < 1:
            raise ValueError(f"flush_every must be an integer ≥ 1, got {flush_every!r}")
        self.folder = prepare_folder(folder, overwrite)
        self.run_id = uuid.uuid4().hex
        self.meta = {**meta, "status": "running", "versions": versions(), "run_id": self.run_id}
        self.flush_every = flush_every
        self._keys: tuple[str, ...] = ()
        self._key_set: frozenset[str] = frozenset()
        self._rows: list[dict[str, np.ndarray]] = []
        self._count = 0
        self._chunks = 0
        (self.folder / CHUNKS).mkdir(exist_ok=True)
        _write_json(self.folder / "meta.json", self.meta)

    def append(self, sample: dict[str, float | np.ndarray]) -> None:
        """Add one sample; every ``flush_every`` samples a chunk is written to disk.

        A sample is kept whole or not at all: it enters the buffer in one list append, so that a
        signal (Ctrl-C, SIGTERM) between two of its keys cannot leave the columns uneven."""
        if not self._keys:
            if RUN_ID_KEY in sample:
                raise ValueError(f"{RUN_ID_KEY!r} is reserved and cannot be a sample key")
            self._keys, self._key_set = tuple(sample), frozenset(sample)
        elif sample.keys() != self._key_set:
            raise ValueError(f"sample keys changed: {sorted(set(sample) ^ self._key_set)}")
        row = {key: np.asarray(value) for key, value in sample.items()}
        self._rows.append(row)
        self._count += 1
        if self._count % self.flush_every == 0:
            self.flush()

    @property
    def samples(self) -> int:
        """The samples appended so far (flushed or still buffered)."""
        return self._count

    def flush(self) -> None:
        """Write the buffered samples as the next chunk (atomically). A signal (Ctrl-C, SIGTERM) while
        it writes leaves the samples buffered and the chunk's number free: the next flush (the one
        ``close`` makes) writes them again under the same name, over the partial file."""
        rows = self._rows
        if not rows:
            return
        arrays = {key: np.stack([row[key] for row in rows]) for key in self._keys}
        _save_npz(self.folder / CHUNKS / f"chunk_{self._chunks + 1:05d}.npz", arrays, self.run_id)
        self._chunks, self._rows = self._chunks + 1, []

    def close(self, summary: dict[str, object] | None = None, status: str = "completed") -> Path:
        """Flush, consolidate the chunks into ``record.npz``, write ``summary.json`` and the status."""
        self.flush()
        chunks = _chunk_files(self.folder)
        data = _concatenate([_read_npz(chunk, self.run_id) for chunk in chunks], chunks)
        if data:
            _save_npz(self.folder / "record.npz", data, self.run_id, compressed=True)
            for chunk in chunks:
                chunk.unlink()
        if summary is not None:
            write_summary(self.folder, summary)
        self.meta["status"] = status
        self.meta["samples"] = self._count
        _write_json(self.folder / "meta.json", self.meta)
        return self.folder


def _chunk_files(folder: Path) -> list[Path]:
    """The finished chunks of a folder in write order (never ``*.partial.npz``)."""
    found = []
    if (folder / CHUNKS).is_dir():
        for path in (folder / CHUNKS).iterdir():
            match = _CHUNK.fullmatch(path.name)
            if match is not None:
                found.append((int(match.group(1)), path))
    return [path for _, path in sorted(found)]


def _read_npz(path: Path, run_id: str | None) -> dict[str, np.ndarray] | None:
    """The arrays of ``path`` if it belongs to run ``run_id`` (an untagged file if None), else None.

    ``ValueError`` naming the file if it is not a readable ``.npz`` of arrays.
    """
    try:
        with np.load(path, allow_pickle=False) as archive:
            owner = str(archive[RUN_ID_KEY]) if RUN_ID_KEY in archive.files else None
            if owner != run_id:
                return None
            return {key: archive[key] for key in archive.files if key != RUN_ID_KEY}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as error:
        reason = " ".join(str(error).split()) or type(error).__name__
        raise ValueError(f"{str(path)!r} is truncated or not a record file ({reason})") from None


def _concatenate(parts: list[dict[str, np.ndarray] | None], paths: list[Path]) -> dict[str, np.ndarray]:
    """The parts that belong to the run (not None), concatenated; ``ValueError`` naming a misfit."""
    kept = [(part, path) for part, path in zip(parts, paths, strict=True) if part is not None]
    if not kept:
        return {}
    keys = kept[0][0].keys()
    for part, path in kept:
        if part.keys() != keys or any(part[key].shape[1:] != kept[0][0][key].shape[1:] for key in keys):
            raise ValueError(f"{str(path)!r} does not match the other chunks of its run (keys or shapes)")
    return {key: np.concatenate([part[key] for part, _ in kept]) for key in keys}


@dataclass(frozen=True)
class Record:
    """A loaded run: time series, metadata and (if the run closed) its summary."""

    folder: Path | None
    data: dict[str, np.ndarray]
    meta: dict[str, object]
    summary: dict[str, object] | None

    def __getitem__(self, key: str) -> np.ndarray:
        return self.data[key]


def load_record(folder: str | Path) -> Record:
    """Read a run folder: the data of the run ``meta.json`` names, from ``record.npz`` if it belongs
    to that run, else from that run's chunks (an interrupted or killed run).

    ``ValueError`` with one line naming the folder or file if it is not a run folder or a file is
    truncated or malformed (its arrays not all one row per sample). A folder written before runs had
    a ``run_id`` reads as it always did.
    """
    path = Path(folder)
    if not (path / "meta.json").is_file():
        raise ValueError(f"{str(path)!r} is not a run folder (no meta.json)")
    meta = _read_json_object(path / "meta.json")
    run_id = meta.get("run_id")
    if run_id is not None and not isinstance(run_id, str):
        raise ValueError(f"{str(path / 'meta.json')!r} has a run_id that is not a string: {run_id!r}")
    consolidated = path / "record.npz"
    data = _read_npz(consolidated, run_id) if consolidated.is_file() else None
    source = consolidated
    if data is None:
        chunks = _chunk_files(path)
        data = _concatenate([_read_npz(chunk, run_id) for chunk in chunks], chunks)
        source = path / CHUNKS
    rows = {key: value.shape[0] if value.ndim else None for key, value in data.items()}
    first = next(iter(rows), None)
    for key, count in rows.items():
        if count != rows[first]:
            raise ValueError(
                f"{str(source)!r} is not one time series: {key!r} has {count} rows, {first!r} {rows[first]}"
            )
    summary_path = path / "summary.json"
    summary = _read_json_object(summary_path) if summary_path.is_file() else None
    return Record(path, data, meta, summary)


def _read_json_object(path: Path) -> dict[str, object]:
    """The JSON object in ``path``; ``ValueError`` naming the file if it is not one."""
    try:
        content = json.loads(path.read_bytes())
    except (OSError, ValueError, RecursionError) as error:
        reason = " ".join(str(error).split())
        raise ValueError(f"{str(path)!r} is not readable JSON ({reason})") from None
    if not isinstance(content, dict):
        raise ValueError(f"{str(path)!r} is not a JSON object (it holds a {type(content).__name__})")
    return content

"""The run record of docs/architecture.md §8, written incrementally so an interrupted run keeps its data.

A run folder holds

``meta.json``
    object, parameters, seed, schedule, versions, and ``status``: ``running``, ``completed`` or
    ``interrupted`` (written first, updated on close);
``chunks/chunk_NNNNN.npz``
    the time series, a chunk every ``flush_every`` samples, each written atomically;
``record.npz``
    all chunks concatenated, written on close (chunks are then removed);
``summary.json``
    the metrics, written on close.

:func:`load_record` reads ``record.npz`` or, after a crash, whatever chunks exist.
"""

from __future__ import annotations

import json
import os
import platform
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

import numpy as np

CHUNKS = "chunks"


def prepare_folder(folder: str | Path) -> Path:
    """Create ``folder`` if needed and check it is writable; ``ValueError`` names it otherwise."""
    path = Path(folder)
    try:
        path.mkdir(parents=True, exist_ok=True)
        probe = path / ".write_probe"
        probe.write_text("")
        probe.unlink()
    except OSError as error:
        raise ValueError(f"cannot write to output folder {str(path)!r}: {error.strerror}") from None
    return path


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


class RecordWriter:
    """Appends samples (dicts of scalars/arrays with fixed keys and shapes) to a run folder."""

    def __init__(self, folder: str | Path, meta: dict[str, object], flush_every: int = 500) -> None:
        self.folder = prepare_folder(folder)
        self.meta = {**meta, "status": "running", "versions": versions()}
        self.flush_every = flush_every
        self._buffer: dict[str, list[np.ndarray]] = {}
        self._count = 0
        self._chunks = 0
        (self.folder / CHUNKS).mkdir(exist_ok=True)
        _write_json(self.folder / "meta.json", self.meta)

    def append(self, sample: dict[str, float | np.ndarray]) -> None:
        """Add one sample; every ``flush_every`` samples a chunk is written to disk."""
        if not self._buffer:
            self._buffer = {key: [] for key in sample}
        elif sample.keys() != self._buffer.keys():
            raise ValueError(f"sample keys changed: {sorted(set(sample) ^ set(self._buffer))}")
        for key, value in sample.items():
            self._buffer[key].append(np.asarray(value))
        self._count += 1
        if self._count % self.flush_every == 0:
            self.flush()

    def flush(self) -> None:
        """Write the buffered samples as the next chunk (atomically)."""
        if not self._buffer or not next(iter(self._buffer.values())):
            return
        self._chunks += 1
        arrays = {key: np.stack(values) for key, values in self._buffer.items()}
        target = self.folder / CHUNKS / f"chunk_{self._chunks:05d}.npz"
        partial = target.with_suffix(".partial.npz")
        np.savez(partial, **arrays)
        os.replace(partial, target)
        self._buffer = {key: [] for key in self._buffer}

    def close(self, summary: dict[str, object] | None = None, status: str = "completed") -> Path:
        """Flush, consolidate the chunks into ``record.npz``, write ``summary.json`` and the status."""
        self.flush()
        data = _read_chunks(self.folder)
        if data:
            partial = self.folder / "record.partial.npz"
            np.savez_compressed(partial, **data)
            os.replace(partial, self.folder / "record.npz")
            for chunk in (self.folder / CHUNKS).glob("chunk_*.npz"):
                chunk.unlink()
        if summary is not None:
            write_summary(self.folder, summary)
        self.meta["status"] = status
        self.meta["samples"] = self._count
        _write_json(self.folder / "meta.json", self.meta)
        return self.folder


def _read_chunks(folder: Path) -> dict[str, np.ndarray]:
    chunks = sorted((folder / CHUNKS).glob("chunk_*.npz"))
    if not chunks:
        return {}
    parts = [dict(np.load(chunk)) for chunk in chunks]
    return {key: np.concatenate([part[key] for part in parts]) for key in parts[0]}


@dataclass(frozen=True)
class Record:
    """A loaded run: time series, metadata and (if the run closed) its summary."""

    folder: Path
    data: dict[str, np.ndarray]
    meta: dict[str, object]
    summary: dict[str, object] | None

    def __getitem__(self, key: str) -> np.ndarray:
        return self.data[key]


def load_record(folder: str | Path) -> Record:
    """Read a run folder; ``ValueError`` if it is not one."""
    path = Path(folder)
    if not (path / "meta.json").is_file():
        raise ValueError(f"{str(path)!r} is not a run folder (no meta.json)")
    meta = json.loads((path / "meta.json").read_text())
    consolidated = path / "record.npz"
    data = dict(np.load(consolidated)) if consolidated.is_file() else _read_chunks(path)
    summary_path = path / "summary.json"
    summary = json.loads(summary_path.read_text()) if summary_path.is_file() else None
    return Record(path, data, meta, summary)

"""The machinery every study shares: trial specs fanned out through an executor, written as they finish.

A study is

* a list of **trial specs**: small frozen dataclasses (or dicts) of JSON-serialisable fields; a
  trial that draws random numbers carries its own ``seed`` (see :func:`trial_seeds`);
* a pure, top-level (picklable) **trial function** ``trial(spec) -> dict`` of JSON-serialisable
  numbers (lists of numbers allowed);
* a summary step: a table printed at the end, figures, :func:`write_results`.

:func:`run_trials` runs the trials through a :mod:`concurrent.futures` executor — in process for one
worker, a :class:`~concurrent.futures.ProcessPoolExecutor` (``spawn``) for several, or a Dask
distributed cluster when a scheduler address is given — and returns the results in spec order. A trial
that raises becomes ``{"error": "<one line>"}``. Every finished trial is appended at once to
``trials.jsonl`` in the study's folder, so an interrupted study keeps what it finished, and
:func:`run_study` resumes it: run again into the same folder, it reuses every trial of
``trials.jsonl`` whose spec equals one of its own and that did not fail, and runs the others
(``--fresh`` starts over; so should a study whose trial code changed).

Trial functions may run in several threads of one Dask worker at once: per-process state that is not
thread-safe (parametrised cvxpy problems, simulators) belongs in a
:func:`thread_cached` builder.

The closed-loop studies share their command-line options (:func:`closed_loop_arguments`), table cells
(:func:`cell`, :func:`slips_cell`) and the stop on Ctrl-C (:func:`finished`).

Each study module has ``main(argv) -> int`` and ``--quick``; every module of this package that defines
``main`` is a study (:func:`ccopt.cliutil.scripts`), run as ``ccopt study NAME``.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import dataclasses
import functools
import json
import multiprocessing
import os
import re
import signal
import sys
import threading
import time
import traceback
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
from tqdm import tqdm

from ccopt.cliutil import OneLineParser, fail, seed_value, write_json
from ccopt.closed_loop import LoopParams, RunResult
from ccopt.config import UNITS
from ccopt.experiment import TOUR_SCHEDULE, experimenter_tour
from ccopt.objects import PlanarObject
from ccopt.schedule import Schedule, load_schedule
from ccopt.stops import STOP_SIGNALS, interrupt, request_stop, stop_requested

Spec = Any
"""A trial spec: a dataclass instance or a dict, JSON-serialisable once through :func:`spec_dict`."""

Trial = Callable[[Spec], dict]
T = TypeVar("T")

TRIALS_LOG = "trials.jsonl"
SCHEDULER_TIMEOUT = "10s"
"""How long to wait for a Dask scheduler before giving up."""


# --- command line ---------------------------------------------------------------------------------


def default_workers() -> int:
    """``min(2, cpu count)``: studies share small machines."""
    return min(2, os.cpu_count() or 1)


def positive_int(value: str) -> int:
    """argparse type: an integer ≥ 1."""
    try:
        number = int(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{value!r} is not an integer") from None
    if number < 1:
        raise argparse.ArgumentTypeError(f"{value!r} must be at least 1")
    return number


def scheduler_address(value: str) -> str:
    """argparse type: a Dask scheduler address ``[tcp|tls]://host:port`` (``host:port`` means tcp)."""
    address = value if "://" in value else f"tcp://{value}"
    match = re.fullmatch(r"(tcp|tls)://([^\s:/]+|\[[0-9a-fA-F:]+\]):(\d{1,5})", address)
    if match is None or not 0 < int(match.group(3)) < 65536:
        raise argparse.ArgumentTypeError(f"{value!r} is not a scheduler address like tcp://127.0.0.1:8786")
    return address


def output_folder(value: str) -> Path:
    """argparse type: a folder that exists or can be created (checked before any work is done)."""
    path = Path(value)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{value!r} exists and is not a folder")
    existing = next(p for p in (path, *path.parents) if p.exists()) if path.parts else Path(".")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"cannot write into {str(existing)!r}")
    return path


def study_parser(name: str, description: str, quick: str, trials: bool = True) -> OneLineParser:
    """The parser of study ``name`` with the shared options; the study adds its own.

    ``--out DIR`` (default ``runs/study-NAME``) and ``--quick`` (``quick`` says what it shrinks) always;
    with ``trials``, also ``--workers N``
    (default :func:`default_workers`), ``--scheduler ADDRESS``, ``--seed``, ``--no-progress`` and
    ``--fresh`` (run every trial again instead of resuming, see :func:`run_study`).
    Bad values end the program with one line on stderr and exit status 2.
    """
    parser = OneLineParser(prog=f"ccopt study {name}", description=description)
    parser.add_argument(
        "--out",
        type=output_folder,
        default=Path(f"runs/study-{name}"),
        metavar="DIR",
        help="output folder, created (default: %(default)s)",
    )
    parser.add_argument("--quick", action="store_true", help=quick)
    if trials:
        parser.add_argument(
            "--workers",
            type=positive_int,
            default=default_workers(),
            metavar="N",
            help="local worker processes; 1 runs in this process (default: %(default)s)",
        )
        parser.add_argument(
            "--scheduler",
            type=scheduler_address,
            metavar="ADDRESS",
            help="run the trials on the Dask cluster at this address, e.g. tcp://127.0.0.1:8786",
        )
        parser.add_argument(
            "--seed", type=seed_value, default=0, help="base seed of the trials, in [0, 2**64) (default: 0)"
        )
        parser.add_argument("--no-progress", action="store_true", help="no progress bar")
        parser.add_argument(
            "--fresh",
            action="store_true",
            help="run every trial again; by default the trials already finished in --out are reused",
        )
    return parser


@dataclass(frozen=True)
class RunOptions:
    """How to run a study's trials (from the shared command-line options)."""

    out: Path
    workers: int = 1
    scheduler: str | None = None
    progress: bool = True
    fresh: bool = False

    @classmethod
    def from_args(cls, args: argparse.Namespace) -> RunOptions:
        return cls(
            out=args.out,
            workers=args.workers,
            scheduler=args.scheduler,
            progress=not args.no_progress,
            fresh=args.fresh,
        )


# --- specs and results ----------------------------------------------------------------------------


def trial_seeds(seed: int, count: int) -> list[int]:
    """``count`` independent 32-bit seeds derived from one base ``seed`` (NumPy ``SeedSequence``)."""
    return [int(child.generate_state(1)[0]) for child in np.random.SeedSequence(seed).spawn(count)]


def spec_dict(spec: Spec) -> dict[str, Any]:
    """A spec as a JSON-ready dict: dataclass fields, enums by value, tuples as lists."""
    fields = dataclasses.asdict(spec) if dataclasses.is_dataclass(spec) else dict(spec)
    return {key: json_ready(value) for key, value in fields.items()}


def json_ready(value: Any) -> Any:
    """``value`` with enums by value, tuples and arrays as lists, NumPy scalars as Python numbers and
    non-finite floats as ``None`` (strict JSON), recursively."""
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, dict):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple | np.ndarray):
        return [json_ready(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def error_line(error: BaseException) -> str:
    """``Type: message``, a multi-line message joined into one line."""
    lines = traceback.format_exception_only(type(error), error)
    text = " ".join(line.strip() for line in lines if line.strip())
    return " ".join(text.split())


def _timed_trial(function: Trial, spec: Spec) -> tuple[dict, float]:
    """Run one trial where it is scheduled; an exception becomes an error row (never a crash)."""
    if stop_requested():  # a pool worker told to stop: no new trial
        raise KeyboardInterrupt
    start = time.perf_counter()
    _IN_TRIAL.set()
    try:
        result = json_ready(dict(function(spec)))
    except Exception as error:  # a failing trial is data, not the end of the study
        result = {"error": error_line(error)}
    finally:
        _IN_TRIAL.clear()
    return result, time.perf_counter() - start


_IN_TRIAL = threading.Event()
"""In a pool worker: whether a trial is running."""


def _pool_worker_start() -> None:
    """Initialise a local pool worker: a stop signal (the study's, forwarded, or Ctrl-C reaching the
    whole process group) interrupts the trial it runs, once, so that its run closes its record, and
    the worker takes no new trial."""
    for number in STOP_SIGNALS:
        signal.signal(number, _stop_worker)


def _stop_worker(signum: int, frame: object) -> None:
    if stop_requested():  # already stopping: let the trial close its record
        return
    request_stop()  # the run's loop polls it too: CasADi may drop the interrupt
    if _IN_TRIAL.is_set():
        interrupt()  # held while the trial's run is being set up


_THREAD_STATE = threading.local()


def thread_cached(build: Callable[..., T]) -> Callable[..., T]:
    """Decorator: call ``build(*args)`` once per thread and argument tuple, then reuse its result.

    Like :func:`functools.cache`, but each thread (each concurrent trial on a Dask worker) gets its
    own object, for state that must not be shared: solvers with parameter values, plants.
    """

    @functools.wraps(build)
    def cached(*args: Any) -> T:
        store = _THREAD_STATE.__dict__.setdefault("store", {})
        key = (build, args)
        if key not in store:
            store[key] = build(*args)
        return store[key]

    return cached


# --- executors ------------------------------------------------------------------------------------


@contextlib.contextmanager
def _executor(workers: int, scheduler: str | None) -> Iterator[Executor]:
    """A Dask cluster's executor when ``scheduler`` is given, else a pool of ``workers`` processes."""
    if scheduler is not None:
        try:
            from distributed import Client
        except ImportError:
            raise RuntimeError("--scheduler needs Dask: pip install 'ccopt[dask]'") from None
        with Client(scheduler, timeout=SCHEDULER_TIMEOUT) as client:
            yield client.get_executor(pure=False)
        return
    # spawn: workers start clean (no forked threads or CasADi buffers), as they would on any OS
    context = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=_pool_worker_start)
    try:
        yield pool
    except BaseException:  # Ctrl-C, a stop signal or a failed write: stop the trials under way
        pool.shutdown(wait=False, cancel_futures=True)
        for worker in multiprocessing.active_children():
            with contextlib.suppress(ProcessLookupError):  # it has just ended
                os.kill(worker.pid, signal.SIGINT)
        raise
    pool.shutdown(wait=True)


def _completed(
    function: Trial, specs: Sequence[Spec], indices: Sequence[int], workers: int, scheduler: str | None
) -> Iterator[tuple[int, dict, float]]:
    """``(index, result, seconds)`` of the trials ``indices`` as each finishes; in process for one
    local worker."""
    if scheduler is None and workers == 1:
        for k in indices:
            yield k, *_timed_trial(function, specs[k])
        return
    with _executor(workers, scheduler) as executor:
        futures = {executor.submit(_timed_trial, function, specs[k]): k for k in indices}
        for future in as_completed(futures):
            try:
                result, seconds = future.result()
            except Exception as error:  # the worker itself died (killed, out of memory, lost)
                result, seconds = {"error": error_line(error)}, float("nan")
            yield futures[future], result, seconds


def run_trials(
    function: Trial,
    specs: Sequence[Spec],
    workers: int = 1,
    scheduler: str | None = None,
    progress: bool = True,
    log: Path | None = None,
    finished: Mapping[int, dict] | None = None,
) -> list[dict]:
    """Run ``function`` on every spec and return the results in spec order.

    Args:
        function: a top-level (picklable) ``trial(spec) -> dict``.
        specs: the trial specs.
        workers: local processes; 1 runs the trials one by one in this process (no pool). Ignored
            when ``scheduler`` is given.
        scheduler: a Dask scheduler address; the trials then run on that cluster.
        progress: show a tqdm bar over completed trials (stderr).
        log: a ``trials.jsonl`` to append each finished trial to, as it finishes:
            ``{"index", "spec", "result", "seconds"}`` per line.
        finished: results already known, by spec index (see :func:`finished_trials`): those trials
            are not run (nor logged) and their results are returned as given.

    A trial that raises yields ``{"error": "<one line>"}``. Raises ``RuntimeError`` if ``scheduler``
    is given but Dask is not installed, ``OSError`` (``TimeoutError``) if the scheduler is unreachable.
    """
    if workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    results = dict(finished or {})
    remaining = [k for k in range(len(specs)) if k not in results]
    bar = tqdm(total=len(specs), initial=len(results), disable=not progress, unit="trial", dynamic_ncols=True)
    with bar:
        for k, result, seconds in _completed(function, specs, remaining, workers, scheduler):
            results[k] = result
            if log is not None:
                record = {"index": k, "spec": spec_dict(specs[k]), "result": result, "seconds": seconds}
                _append_line(log, record)
            bar.update()
    return [results[k] for k in range(len(specs))]


def _append_line(path: Path, record: dict) -> None:
    with open(path, "a") as stream:
        stream.write(json.dumps(json_ready(record)) + "\n")
        stream.flush()


def run_study(prog: str, function: Trial, specs: Sequence[Spec], options: RunOptions) -> list[dict]:
    """:func:`run_trials` for a study's command line, into ``options.out`` (created), resumed.

    The trials already finished in ``options.out``'s ``trials.jsonl`` (:func:`finished_trials`) are
    reused and the log is rewritten to hold just them; the others run and are appended. With
    ``options.fresh`` the log starts empty and every trial runs. An unreachable scheduler or an
    unwritable folder ends the program with one line (exit 2); Ctrl-C with one line (exit 130), the
    finished trials kept in ``trials.jsonl``.
    """
    log = options.out / TRIALS_LOG
    try:
        options.out.mkdir(parents=True, exist_ok=True)
        kept = {} if options.fresh or not log.is_file() else finished_trials(read_trials(log), specs)
        _rewrite_log(log, [kept[k] for k in sorted(kept)])
        if kept:
            sys.stderr.write(
                f"{prog}: resuming: {len(kept)} of {len(specs)} trials already finished in {log} "
                "(--fresh runs them again)\n"
            )
        finished = {k: record["result"] for k, record in kept.items()}
        return run_trials(
            function, specs, options.workers, options.scheduler, options.progress, log, finished
        )
    except (OSError, TimeoutError, RuntimeError) as error:
        fail(prog, error_line(error))
    except KeyboardInterrupt:
        sys.stderr.write(f"{prog}: interrupted; finished trials are in {log}\n")
        raise SystemExit(130) from None


def _rewrite_log(log: Path, records: Sequence[dict]) -> None:
    """Replace ``log`` atomically with ``records``, one JSON line each."""
    partial = log.with_name(log.name + ".partial")
    partial.write_text("".join(json.dumps(json_ready(record)) + "\n" for record in records))
    os.replace(partial, log)


def read_trials(path: Path) -> list[dict]:
    """The records of a ``trials.jsonl`` (finished trials, in completion order).

    The log may have been cut short (a killed study leaves a partial last line) or damaged: lines
    that are not JSON objects are left out.
    """
    records = []
    with open(path, encoding="utf-8", errors="replace") as stream:
        for line in stream:
            try:
                record = json.loads(line)
            except (ValueError, RecursionError):
                continue
            if isinstance(record, dict):
                records.append(record)
    return records


def spec_key(spec: Spec) -> str:
    """A spec's identity: its :func:`spec_dict` as canonical JSON (the same after a round trip
    through ``trials.jsonl``)."""
    return json.dumps(spec_dict(spec), sort_keys=True)


def finished_trials(records: Sequence[dict], specs: Sequence[Spec]) -> dict[int, dict]:
    """The log records (``{"index", "spec", "result", "seconds"}``) that finish some of ``specs``,
    by spec index, each with its ``index`` set to that spec's.

    A record finishes every spec equal to its ``spec`` (:func:`spec_key`) if its ``result`` is a
    dict without ``"error"``; the latest such record counts. Records of other specs are left out.
    """
    by_key: dict[str, dict] = {}
    for record in records:
        result, spec = record.get("result"), record.get("spec")
        if isinstance(result, dict) and "error" not in result and isinstance(spec, dict):
            by_key[spec_key(spec)] = record
    found = {}
    for k, spec in enumerate(specs):
        record = by_key.get(spec_key(spec))
        if record is not None:
            found[k] = {**record, "index": k}
    return found


CSV_LIST_MOST = 16
"""Longest list a ``results.csv`` cell holds (its items joined by ``;``); longer ones (traces, grids)
are in ``results.json`` only."""


def csv_row(row: Mapping[str, Any]) -> dict[str, Any]:
    """A flat CSV row of a JSON-ready mapping: nested mappings as ``outer.inner`` columns, a list of up
    to :data:`CSV_LIST_MOST` plain values as its items joined by ``;`` (None empty), longer lists and
    lists of mappings left out; never a JSON array in a cell."""
    flat: dict[str, Any] = {}
    for key, value in row.items():
        if isinstance(value, Mapping):
            flat.update({f"{key}.{inner}": item for inner, item in csv_row(value).items()})
        elif isinstance(value, list):
            plain = all(not isinstance(item, list | Mapping) for item in value)
            if plain and len(value) <= CSV_LIST_MOST:
                flat[key] = ";".join("" if item is None else str(item) for item in value)
        else:
            flat[key] = value
    return flat


def write_results(
    out: Path, specs: Sequence[Spec], results: Sequence[dict], summary: dict, units: str = UNITS
) -> None:
    """``results.json`` (``units``, the summary and every trial) and ``results.csv`` (one flat row per
    trial, :func:`csv_row`: the spec's fields then the result's) in ``out``."""
    rows = [{**spec_dict(spec), **json_ready(result)} for spec, result in zip(specs, results, strict=True)]
    write_json(
        out / "results.json",
        {
            "units": units,
            "summary": json_ready(summary),
            "trials": [
                {"spec": spec_dict(s), "result": json_ready(r)} for s, r in zip(specs, results, strict=True)
            ],
        },
    )
    flat = [csv_row(row) for row in rows]
    columns = list(dict.fromkeys(key for row in flat for key in row))
    with open(out / "results.csv", "w", newline="") as stream:
        writer = csv.DictWriter(stream, fieldnames=columns)
        writer.writeheader()
        writer.writerows(flat)


def failures(results: Sequence[dict]) -> list[tuple[int, str]]:
    """``(index, message)`` of the trials that raised."""
    return [(k, r["error"]) for k, r in enumerate(results) if "error" in r]


# --- shared by the closed-loop studies ------------------------------------------------------------


def finished(result: RunResult) -> RunResult:
    """``result``, or ``KeyboardInterrupt`` again if Ctrl-C ended the run (the study must stop too)."""
    if result.interrupted:
        raise KeyboardInterrupt
    return result


def cell(value: object, digits: int = 2) -> str:
    """A table cell: numbers rounded, ``None`` as ``n/a``."""
    if value is None:
        return "n/a"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


def slips_cell(row: Mapping[str, object]) -> str:
    """``total (g ground slides, h hand slides, p hand pivots)`` of a ``flat_summary`` row."""
    parts = " ".join(
        f"{tag}{row[f'slips_{name}']}"
        for tag, name in (("g", "ground_slide"), ("h", "hand_slide"), ("p", "hand_pivot"))
    )
    return f"{row['unintended_slips']} ({parts})"


QUICK_SCHEDULE = "smoke"
"""The schedule of a closed-loop study run with ``--quick`` (unless ``--schedule`` names one)."""


def closed_loop_arguments(parser: argparse.ArgumentParser, schedule: str = "paper") -> None:
    """``--schedule`` (default ``schedule``, :data:`QUICK_SCHEDULE` with ``--quick``) and ``--plant``,
    shared by the closed-loop studies; :func:`checked_schedule` reads the schedule chosen."""
    parser.add_argument(
        "--schedule",
        help=f"built-in (paper, smoke), a .yaml/.json file, or {TOUR_SCHEDULE}: each object's own tour of "
        f"the motions its true statics allow (default: {schedule}; with --quick: {QUICK_SCHEDULE})",
    )
    parser.set_defaults(default_schedule=schedule)
    parser.add_argument(
        "--plant", choices=("planar", "panda"), default="planar", help="simulated robot (default: planar)"
    )


def trial_run(obj: PlanarObject, schedule: str, params: LoopParams) -> tuple[Schedule, LoopParams]:
    """The schedule and loop parameters of a trial of ``obj``: the schedule named (a built-in or a
    file), or for :data:`~ccopt.experiment.TOUR_SCHEDULE` the object's own tour and the start it
    needs (:func:`ccopt.experiment.experimenter_tour`)."""
    if schedule == TOUR_SCHEDULE:
        tour_params, tour = experimenter_tour(obj, params)
        return tour.schedule, tour_params
    return load_schedule(schedule), params


def checked_schedule(prog: str, args: argparse.Namespace) -> str:
    """The schedule a closed-loop study's ``args`` choose (see :func:`closed_loop_arguments`), checked:
    its name or file, or one line and exit 2; :data:`~ccopt.experiment.TOUR_SCHEDULE` is made per
    object (:func:`trial_run`)."""
    name = args.schedule or (QUICK_SCHEDULE if args.quick else args.default_schedule)
    if name == TOUR_SCHEDULE:
        return name
    try:
        load_schedule(name)
    except ValueError as error:
        fail(prog, str(error))
    return name

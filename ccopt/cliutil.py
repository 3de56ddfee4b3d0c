"""Command-line plumbing shared by ``ccopt``'s CLI, the studies and the benchmarks: one-line errors,
argument types, the stop signals, JSON output."""

from __future__ import annotations

import argparse
import ast
import contextlib
import importlib.util
import json
import os
import pkgutil
import signal
import sys
import threading
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import NoReturn

from ccopt.validation import short

MAX_SEED = 2**64
"""Seeds are integers in ``[0, MAX_SEED)``."""
INTERRUPTED = 130
"""Exit status of a program stopped by Ctrl-C or a stop signal (128 + SIGINT)."""
STOP_SIGNALS = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
)
"""The signals that stop a run or a study as Ctrl-C does (:func:`stop_signals`)."""


class OneLineParser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are a single line on stderr and exit status 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def fail(prog: str, message: str) -> NoReturn:
    """Print ``prog: error: message`` on one line and exit with status 2 (bad input)."""
    sys.stderr.write(f"{prog}: error: {message}\n")
    raise SystemExit(2)


def fail_lines(prog: str, messages: Sequence[str]) -> NoReturn:
    """Print ``prog: error: message`` for each message, one line each, and exit with status 2."""
    for message in messages:
        sys.stderr.write(f"{prog}: error: {message}\n")
    raise SystemExit(2)


def seed_value(value: str) -> int:
    """argparse type: a seed, an integer in ``[0, 2**64)``."""
    try:
        number = int(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"seed {short(value)} is not an integer") from None
    if not 0 <= number < MAX_SEED:
        raise argparse.ArgumentTypeError(f"seed must be an integer in [0, 2**64), got {short(value)}")
    return number


_stopping = threading.Event()
"""Set by the first stop signal: the program is on its way out (:func:`stop_requested`)."""
_held = threading.Event()
"""Set by a stop signal that came within :func:`stops_held`: it is raised when the block ends."""
_holding = [0]
"""How deep the main thread is in :func:`stops_held` blocks."""


@contextlib.contextmanager
def stop_signals(prog: str) -> Iterator[None]:
    """Within: SIGTERM and SIGHUP stop the program as Ctrl-C does, by ``KeyboardInterrupt`` in the main
    thread (a run then closes its record). Once one of the three has come, the next one ends the
    program at once and quietly: ``prog: ...`` on one line and exit status :data:`INTERRUPTED`, no
    traceback; so that this holds to the end, the handlers are then left in place. It ends the
    process outright (``os._exit``, after flushing stdout and stderr): an exception raised from the
    handler could be lost, as when CasADi runs the handlers from its C++ code and raises its own
    ``KeyboardInterrupt`` in place of theirs.

    Outside the main thread (where handlers cannot be set) it changes nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handle(signum: int, frame: object) -> None:
        if _stopping.is_set():
            sys.stderr.write(f"{prog}: {signal.Signals(signum).name} again: stopping now\n")
            for stream in (sys.stdout, sys.stderr):
                with contextlib.suppress(OSError, ValueError):  # a closed pipe, a closed stream
                    stream.flush()
            os._exit(INTERRUPTED)
        _stopping.set()
        interrupt()

    previous = {number: signal.signal(number, handle) for number in STOP_SIGNALS}
    try:
        yield
    finally:
        if not _stopping.is_set():
            for number, handler in previous.items():
                signal.signal(number, handler)


def stop_requested() -> bool:
    """Whether a stop signal has come under :func:`stop_signals` (or :func:`request_stop` was called):
    the program is on its way out. Long work polls it, because the ``KeyboardInterrupt`` a handler
    raises can be lost: CasADi, building a function (symbolic operations, ``casadi.Function``), runs
    the handlers from its C++ code and at times drops what they raise (2 times in 20 interrupts of a
    loop building functions; a Panda run stopped while its oracle built its LP exited 0, 2 times in
    40)."""
    return _stopping.is_set()


def request_stop() -> None:
    """Mark the program as on its way out (:func:`stop_requested`): for a stop signal handler of its
    own (a study's pool worker)."""
    _stopping.set()


def interrupt(*_: object) -> None:
    """What a stop signal's handler does once it has decided to stop: raise ``KeyboardInterrupt``,
    or hold it until the :func:`stops_held` block ends (unless one is held already: the user
    insists). Every handler goes through it, so that held set-up holds whatever stops it."""
    if _holding[0] and not _held.is_set():
        _held.set()
        return
    raise KeyboardInterrupt


@contextlib.contextmanager
def stops_held() -> Iterator[None]:
    """Within: a stop signal does not interrupt the block; it is raised as ``KeyboardInterrupt`` when
    the block ends (over an exception the block raised: the user asked to stop). For set-up that an
    interrupt would not stop but corrupt: a C extension's module initialisation turns it into
    ``ImportError: initialization failed``, CasADi building a function may drop it
    (:func:`stop_requested`), and once a Panda run stopped while it started was killed by SIGINT
    after it had handled the interrupt (4 of 40 such runs went wrong before its set-up was held and
    the loop polled, 0 of 80 after). Under :func:`stop_signals` it holds all three stop signals (a
    second one still ends the program at once); otherwise Ctrl-C, as long as no other handler than
    Python's own is set (a second Ctrl-C then interrupts at once).

    Outside the main thread (where signals are not handled) it changes nothing. Blocks nest: the
    outermost one raises.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    own = signal.getsignal(signal.SIGINT) is signal.default_int_handler
    previous = signal.signal(signal.SIGINT, interrupt) if own else None
    _holding[0] += 1
    try:
        yield
    finally:
        _holding[0] -= 1
        if own:
            signal.signal(signal.SIGINT, previous)
        if not _holding[0] and _held.is_set():
            _held.clear()
            raise KeyboardInterrupt


def writable_json_path(value: str) -> Path:
    """argparse type: a path whose folder exists and is writable (checked before any work is done)."""
    path = Path(value)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise argparse.ArgumentTypeError(f"folder of {value!r} does not exist")
    try:
        with open(path, "a"):
            pass
    except OSError as error:
        raise argparse.ArgumentTypeError(f"cannot write {value!r}: {error.strerror}") from None
    return path


def benchmark_parser(name: str, doc: str, quick: str, seed: str | None = None) -> OneLineParser:
    """The parser every benchmark shares: ``--quick`` (``quick`` says what it shrinks), ``--json PATH``
    and, with a ``seed`` help text, ``--seed``."""
    parser = OneLineParser(prog=f"ccopt bench {name}", description=doc.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help=quick)
    parser.add_argument("--json", type=writable_json_path, metavar="PATH", help="write the figures here")
    if seed is not None:
        parser.add_argument("--seed", type=seed_value, default=0, help=seed)
    return parser


def write_json(path: Path, figures: dict[str, object]) -> None:
    """Write ``figures`` as pretty JSON to ``path``."""
    path.write_text(json.dumps(figures, indent=2, sort_keys=True) + "\n")


def print_table(rows: list[tuple[str, ...]], header: tuple[str, ...]) -> None:
    """Print a small left-aligned text table."""
    widths = [max(len(str(r[i])) for r in [header, *rows]) for i in range(len(header))]
    for row in [header, tuple("-" * w for w in widths), *rows]:
        print("  ".join(str(cell).ljust(width) for cell, width in zip(row, widths, strict=True)))


def scripts(package: str) -> dict[str, str]:
    """The runnable scripts of ``package`` (``studies``, ``benchmarks``): every module of it, not private,
    that defines a top-level ``main``, by name, with the first line of its docstring. Read from the
    source, nothing imported (listing the studies loads none of them); ``{}`` if the package is absent."""
    spec = importlib.util.find_spec(package)
    if spec is None or not spec.submodule_search_locations:
        return {}
    found = {}
    for module in sorted(pkgutil.iter_modules(spec.submodule_search_locations), key=lambda m: m.name):
        if module.name.startswith("_") or module.ispkg:
            continue
        source = importlib.util.find_spec(f"{package}.{module.name}").origin
        tree = ast.parse(Path(source).read_text(encoding="utf-8"))
        if any(isinstance(node, ast.FunctionDef) and node.name == "main" for node in tree.body):
            found[module.name] = (ast.get_docstring(tree) or "").strip().split("\n")[0]
    return found


def print_scripts(title: str, found: dict[str, str], usage: str) -> None:
    """List ``found`` (name → one line) under ``title``, then ``usage``."""
    print(title)
    width = max((len(name) for name in found), default=0)
    for name, line in found.items():
        print(f"  {name.ljust(width)}  {line}")
    print(usage)

"""Command-line plumbing shared by ``ccopt``'s CLI, the studies and the benchmarks: one-line errors,
argument types, JSON output (the stop signals: :mod:`ccopt.stops`)."""

from __future__ import annotations

import argparse
import ast
import importlib.util
import json
import pkgutil
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

from ccopt.validation import short

MAX_SEED = 2**64
"""Seeds are integers in ``[0, MAX_SEED)``."""


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

"""Command-line plumbing shared by ``ccopt``'s CLI and the benchmarks: one-line errors, JSON output."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import NoReturn


class OneLineParser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are a single line on stderr and exit status 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def fail(prog: str, message: str) -> NoReturn:
    """Print ``prog: error: message`` on one line and exit with status 2 (bad input)."""
    sys.stderr.write(f"{prog}: error: {message}\n")
    raise SystemExit(2)


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
    parser = OneLineParser(prog=f"python -m benchmarks.{name}", description=doc.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help=quick)
    parser.add_argument("--json", type=writable_json_path, metavar="PATH", help="write the figures here")
    if seed is not None:
        parser.add_argument("--seed", type=int, default=0, help=seed)
    return parser


def write_json(path: Path, figures: dict[str, object]) -> None:
    """Write ``figures`` as pretty JSON to ``path``."""
    path.write_text(json.dumps(figures, indent=2, sort_keys=True) + "\n")


def print_table(rows: list[tuple[str, ...]], header: tuple[str, ...]) -> None:
    """Print a small left-aligned text table."""
    widths = [max(len(str(r[i])) for r in [header, *rows]) for i in range(len(header))]
    for row in [header, tuple("-" * w for w in widths), *rows]:
        print("  ".join(str(cell).ljust(width) for cell, width in zip(row, widths, strict=True)))

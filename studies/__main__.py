"""``python -m studies NAME [ARGS]``: run one study (``--help`` after NAME for its options)."""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from ccopt.cliutil import OneLineParser, fail
from studies.runner import study_modules


def main(argv: Sequence[str] | None = None) -> int:
    names = study_modules()
    parser = OneLineParser(prog="python -m studies", description="Run a scripted study.")
    parser.add_argument("name", help="one of: " + ", ".join(names))
    parser.add_argument("rest", nargs=argparse.REMAINDER, help="the study's own arguments")
    args = parser.parse_args(argv)
    if args.name not in names:
        fail(parser.prog, f"unknown study {args.name!r}; expected one of: {', '.join(names)}")
    return importlib.import_module(names[args.name]).main(args.rest)


if __name__ == "__main__":
    sys.exit(main())

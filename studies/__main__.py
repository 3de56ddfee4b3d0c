"""``python -m studies NAME [ARGS]``: run one study (``--help`` after NAME for its options).

Ctrl-C, SIGTERM and SIGHUP stop a study alike (exit status 130, the finished trials kept in its
``trials.jsonl``); a second one ends it at once.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from ccopt.cliutil import INTERRUPTED, OneLineParser, fail, stop_signals
from studies.runner import study_modules


def main(argv: Sequence[str] | None = None) -> int:
    names = study_modules()
    parser = OneLineParser(prog="python -m studies", description="Run a scripted study.")
    parser.add_argument("name", help="one of: " + ", ".join(names))
    parser.add_argument("rest", nargs=argparse.REMAINDER, help="the study's own arguments")
    args = parser.parse_args(argv)
    if args.name not in names:
        fail(parser.prog, f"unknown study {args.name!r}; expected one of: {', '.join(names)}")
    prog = f"{parser.prog} {args.name}"
    with stop_signals(prog):
        try:
            return importlib.import_module(names[args.name]).main(args.rest)
        except KeyboardInterrupt:
            sys.stderr.write(f"{prog}: interrupted\n")
            return INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())

"""``ccopt study NAME [ARGS]`` (or ``python -m studies NAME [ARGS]``): run one study (``--help`` after
NAME for its options); without NAME, list the studies, one line each.

Ctrl-C, SIGTERM and SIGHUP stop a study alike (exit status 130, the finished trials kept in its
``trials.jsonl``); a second one ends it at once.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from ccopt.cliutil import OneLineParser, fail, print_scripts, scripts
from ccopt.stops import INTERRUPTED, stop_signals

PROG = "ccopt study"


def main(argv: Sequence[str] | None = None) -> int:
    studies = scripts("studies")
    parser = OneLineParser(prog=PROG, description="Run a scripted study; without NAME, list them.")
    parser.add_argument("name", nargs="?", help="one of: " + ", ".join(studies))
    parser.add_argument("rest", nargs=argparse.REMAINDER, help="the study's own arguments")
    args = parser.parse_args(argv)
    if args.name is None:
        print_scripts(
            "studies:", studies, f"run one with '{PROG} NAME [--quick]'; '{PROG} NAME --help' for its options"
        )
        return 0
    if args.name not in studies:
        fail(PROG, f"unknown study {args.name!r}; expected one of: {', '.join(studies)}")
    prog = f"{PROG} {args.name}"
    with stop_signals(prog):
        try:
            return importlib.import_module(f"studies.{args.name}").main(args.rest)
        except KeyboardInterrupt:
            sys.stderr.write(f"{prog}: interrupted\n")
            return INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())

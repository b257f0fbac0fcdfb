"""The ``sphereplan`` command line.

Each verb lives in its own module of this package and exposes ``VERB`` (its name), ``HELP`` (one line)
and ``add_arguments(parser)``; the parser's ``func`` default takes the parsed arguments and returns the
exit code. Verbs are discovered, so a new capability adds one module and nothing else.

Exit codes (docs/contracts.md) come from the one outcome table (:mod:`service.outcome`): 0 success,
2 bad input (the message on stderr names the field; a start or goal outside the map or occupied too),
3 no solution exists, 4 timeout.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import pkgutil
import sys
from collections.abc import Sequence

from planner import __version__
from planner.errors import SpherePlanError
from service.outcome import EXIT_BAD_INPUT, answer_for


class _Parser(argparse.ArgumentParser):
    """argparse that exits with code 2 and a one-line message naming the bad option."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.print_usage(sys.stderr)
        sys.stderr.write(f"{self.prog}: error: {message}\n")
        raise SystemExit(EXIT_BAD_INPUT)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="sphereplan", description="Motion planning for spherical rolling robots.")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress to stderr")
    parser.add_argument("--version", action="version", version=f"sphereplan {__version__}")
    sub = parser.add_subparsers(dest="verb", required=True, parser_class=_Parser)
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        verb_parser = sub.add_parser(module.VERB, help=module.HELP, description=module.HELP)
        module.add_arguments(verb_parser)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``sphereplan`` console script; returns the exit code."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: --help (0) or a bad option (2, message already on stderr)
        return int(exc.code or 0) if not isinstance(exc.code, str) else EXIT_BAD_INPUT
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING, format="%(levelname)s %(message)s")
    try:
        return int(args.func(args))
    except SpherePlanError as exc:
        answer = answer_for(exc)
        sys.stderr.write(f"sphereplan {args.verb}: {answer.cli_label}: {exc}\n")
        return answer.exit_code
    except RecursionError:  # json.loads of an absurdly nested --options or input file
        sys.stderr.write(f"sphereplan {args.verb}: error: an input is nested too deeply\n")
        return EXIT_BAD_INPUT
    except Exception as exc:  # a bug: one line, exit 1; the traceback only with --verbose
        logging.getLogger(__name__).debug("%s failed", args.verb, exc_info=True)
        answer = answer_for(exc)
        sys.stderr.write(f"sphereplan {args.verb}: {answer.cli_label}: {type(exc).__name__}: {exc} "
                         "(a bug: run with -v for the traceback)\n")
        return answer.exit_code


if __name__ == "__main__":
    raise SystemExit(main())

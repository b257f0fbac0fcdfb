"""The ``sphereplan`` command line.

Each verb lives in its own module of this package and exposes ``VERB`` (its name), ``HELP`` (one line)
and ``add_arguments(parser)``; the parser's ``func`` default takes the parsed arguments and returns the
exit code. Verbs are discovered, so a new capability adds one module and nothing else. A verb module
imports only argparse-level things at the top and its planner modules inside ``run``: ``--help`` builds
every verb's parser, and must not pay for numba, scipy or matplotlib (tests/service/test_cli_docs.py).

Progress and logs go to stderr (stdout may carry JSON): ``-q`` silences the progress, ``-v`` adds INFO logs
and stage times, ``-vv`` DEBUG; long verbs report their stages through :class:`service.cli._io.Stages`.

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
from service.cli._io import make_output_folders, set_verbosity
from service.outcome import EXIT_BAD_INPUT, answer_for


class _Parser(argparse.ArgumentParser):
    """argparse that exits with code 2 and a one-line message naming the bad option."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.print_usage(sys.stderr)
        sys.stderr.write(f"{self.prog}: error: {message}\n")
        raise SystemExit(EXIT_BAD_INPUT)


def _add_talk_flags(parser: argparse.ArgumentParser, top: bool) -> None:
    """``-v``/``-q`` on the tool and on every verb (``sphereplan -q plan …`` = ``sphereplan plan … -q``).

    A verb's copy has no default, so it does not overwrite what was given before the verb.
    """
    talk = parser.add_mutually_exclusive_group()
    talk.add_argument("-v", "--verbose", action="count", default=0 if top else argparse.SUPPRESS,
                      help="log what happens to stderr (-vv: debug); progress is on stderr by default")
    talk.add_argument("-q", "--quiet", action="store_true", default=False if top else argparse.SUPPRESS,
                      help="no progress, only errors on stderr")


def _add_talk_flags_below(parser: argparse.ArgumentParser, seen: set[int]) -> None:
    """The same flags on every sub-verb (``sphereplan vpip schedule … -q``), however deep."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                if id(child) not in seen:
                    seen.add(id(child))
                    _add_talk_flags(child, top=False)
                    _add_talk_flags_below(child, seen)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="sphereplan", description="Motion planning for spherical rolling robots.")
    _add_talk_flags(parser, top=True)
    parser.add_argument("--version", action="version", version=f"sphereplan {__version__}")
    sub = parser.add_subparsers(dest="verb", required=True, parser_class=_Parser)
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        verb_parser = sub.add_parser(module.VERB, help=module.HELP, description=module.HELP)
        _add_talk_flags(verb_parser, top=False)
        module.add_arguments(verb_parser)
        _add_talk_flags_below(verb_parser, set())
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``sphereplan`` console script; returns the exit code."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: --help (0) or a bad option (2, message already on stderr)
        return int(exc.code or 0) if not isinstance(exc.code, str) else EXIT_BAD_INPUT
    verbosity = -1 if args.quiet else min(args.verbose, 2)
    set_verbosity(verbosity)
    level = {-1: logging.ERROR, 0: logging.WARNING, 1: logging.INFO, 2: logging.DEBUG}[verbosity]
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)
    try:
        make_output_folders(args)
        return int(args.func(args))
    except SpherePlanError as exc:
        answer = answer_for(exc)
        text = str(exc)
        # one prefix per message: a planner message that already starts with the label ("no path: ...") keeps its own
        label = "" if text.startswith(f"{answer.cli_label}:") else f"{answer.cli_label}: "
        sys.stderr.write(f"sphereplan {args.verb}: {label}{text}\n")
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

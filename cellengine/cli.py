"""The `cellengine` command: a thin main that dispatches to one module per command."""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence

from cellengine import __version__
from cellengine.errors import EXIT_USAGE, CellError

# A reader that went away (`cellengine show CELL | head`): 128 + SIGPIPE, as a shell reports a
# program its pipe's reader left
EXIT_BROKEN_PIPE = 141

# each command's module (cellengine.commands.*), imported when the parser needs it
COMMANDS = {
    "validate": "validate",
    "sweep": "sweep",
    "plan": "plan",
    "run": "run",
    "show": "show",
    "schema": "schema",
    "import": "import_remodel",
    "emulate": "emulate",
    "locate": "locate",
}


def parser(only: str | None = None) -> argparse.ArgumentParser:
    """The command line's parser; ``only``: with that command alone, the others' modules
    not imported (~25 ms of a plan's start: most of what they import, plan imports too)."""
    p = argparse.ArgumentParser(
        prog="cellengine", description="Program dual-arm robot cells from files."
    )
    p.add_argument("--version", action="version", version=f"cellengine {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, module in COMMANDS.items():
        if only is None or name == only:
            importlib.import_module(f"cellengine.commands.{module}").add_parser(sub, name)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    # a command named first is parsed by its own parser alone; anything else (--help, no
    # command, one mistyped) by the whole parser, which lists every command
    args = parser(argv[0] if argv and argv[0] in COMMANDS else None).parse_args(argv)
    try:
        code: int = args.run(args)
    except CellError as e:
        for problem in e.problems:
            print(problem, file=sys.stderr)
        return e.exit_code
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return EXIT_USAGE
    return code


def entry() -> None:
    """The `cellengine` program. When the reader of its output goes away (`... | head`), it
    stops quietly: no traceback, and stdout goes to devnull so that the flush at exit does
    not fail again (the Python docs' advice, signal module, "Note on SIGPIPE")."""
    try:
        code = main()
        sys.stdout.flush()
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        code = EXIT_BROKEN_PIPE
    sys.exit(code)


if __name__ == "__main__":
    entry()

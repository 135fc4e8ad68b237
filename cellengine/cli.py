"""The `cellengine` command: a thin main that dispatches to one module per command."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence

from cellengine import __version__
from cellengine.commands import emulate, import_remodel, plan, run, schema, show, validate
from cellengine.errors import EXIT_USAGE, CellError

# A reader that went away (`cellengine show CELL | head`): 128 + SIGPIPE, as a shell reports a
# program its pipe's reader left
EXIT_BROKEN_PIPE = 141

COMMANDS = {
    "validate": validate,
    "plan": plan,
    "run": run,
    "show": show,
    "schema": schema,
    "import": import_remodel,
    "emulate": emulate,
}


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="cellengine", description="Program dual-arm robot cells from files."
    )
    p.add_argument("--version", action="version", version=f"cellengine {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, module in COMMANDS.items():
        module.add_parser(sub, name)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = parser().parse_args(argv)
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

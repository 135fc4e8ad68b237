"""The `cellengine` command: a thin main that dispatches to one module per command."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from cellengine.commands import emulate, import_remodel, plan, run, schema, show, validate
from cellengine.errors import EXIT_USAGE, CellError

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
    """The `cellengine` program."""
    sys.exit(main())


if __name__ == "__main__":
    entry()

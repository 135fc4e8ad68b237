"""The `cellengine` command: a thin main that dispatches to one module per command."""

from __future__ import annotations

import argparse
import os
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
    """The `cellengine` program: main(), then exit. A process that had to leave a vendor
    client behind (a UR controller that went away mid-call) ends at once, its output
    flushed: the client's threads would crash the interpreter's teardown."""
    code = main()
    left = sys.modules.get("cellengine.drivers.ur_rtde")
    if left is not None and left.clients_left_behind():
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":
    entry()

"""The `gigascroll` command line. Each subcommand lives in gigascroll.commands.<name>
and exposes `register(subparsers)`; the parser sets `func(args) -> int` on the namespace.
Errors the user can fix (bad files, bad parameters) print one line and exit with 2."""

from __future__ import annotations

import argparse
import sys

from .commands import bench, demo, export, gallery, info, pack, render, scenario, serve, synth, view
from .errors import UserError

# Subcommand modules, in the order `gigascroll --help` lists them.
COMMANDS = [demo, synth, pack, info, export, bench, render, scenario, gallery, view, serve]


# Integer options the core takes as fixed-width integers: checked when parsed, so a value
# out of range is a one-line usage error instead of a binding's TypeError. Others: int64.
INT_RANGES = {"seed": (0, 2**64 - 1), "threads": (0, 4096), "width": (-2**31, 2**31 - 1),
              "height": (-2**31, 2**31 - 1)}
INT64 = (-2**63, 2**63 - 1)


def _checked_int(dest: str):
    lo, hi = INT_RANGES.get(dest, INT64)

    def parse(text: str) -> int:
        value = int(text)  # ValueError: argparse says "invalid int value"
        if not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"{value if len(str(value)) < 30 else 'value'} "
                                             f"is out of range [{lo}, {hi}]")
        return value
    parse.__name__ = "int"
    return parse


def _check_int_options(parser: argparse.ArgumentParser) -> None:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sp in action.choices.values():
                _check_int_options(sp)
        elif action.type is int:
            action.type = _checked_int(action.dest)


class _Parser(argparse.ArgumentParser):
    """argparse with its usage errors as one line (the usage itself is one --help away), as
    every other error of the command; subcommands' parsers are of the same class."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="gigascroll",
        description="Gigapixel paintings in VR: virtual texturing and photon mapping.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for module in COMMANDS:
        module.register(sub)
    _check_int_options(parser)
    return parser


def _one_line(e: BaseException) -> str:
    return " ".join(str(e).split()) or type(e).__name__


def main(argv: list[str] | None = None) -> int:
    from .outputs import ignore_sigxfsz
    ignore_sigxfsz()  # past a file-size limit a write fails (EFBIG) and is reported, not fatal
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (UserError, ValueError, OSError) as e:
        print(f"gigascroll {args.command}: error: {_one_line(e)}", file=sys.stderr)
        return 2
    except MemoryError as e:  # sizes the core could not allocate: one line, not a traceback
        print(f"gigascroll {args.command}: error: not enough memory for these sizes "
              f"({_one_line(e)})", file=sys.stderr)
        return 2
    except RecursionError:  # e.g. a JSON file nested thousands deep, read by a library
        print(f"gigascroll {args.command}: error: input nested too deeply to read",
              file=sys.stderr)
        return 2
    except TypeError as e:
        # A value the core's binding cannot take (out of its integer range): the option
        # checks above should catch these first; never a traceback for them.
        if "incompatible function arguments" not in str(e):
            raise
        first = str(e).splitlines()[0]
        print(f"gigascroll {args.command}: error: a value is out of the range the core "
              f"accepts ({first})", file=sys.stderr)
        return 2
    except KeyboardInterrupt as e:  # SIGINT, or SIGTERM / SIGHUP during a build
        signum = getattr(e, "signum", 2)
        print(f"gigascroll {args.command}: interrupted{f' ({e})' if signum != 2 else ''}",
              file=sys.stderr)
        return 128 + signum

"""The `gigascroll` command line. Each subcommand lives in gigascroll.commands.<name>
and exposes `register(subparsers)`; the parser sets `func(args) -> int` on the namespace.
Errors the user can fix (bad files, bad parameters) print one line and exit with 2; when
standard output's reader goes away (`gigascroll info --json PACK | head`) the command ends
quietly with 141, as Unix tools killed by SIGPIPE do."""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import select
import signal
import sys

from .commands import (bench, demo, exhibit, export, gallery, info, light, pack, render, scenario,
                       serve, synth, view)
from .errors import UserError

# Subcommand modules, in the order `gigascroll --help` lists them.
COMMANDS = [demo, synth, pack, info, export, bench, render, scenario, gallery, light, view, serve,
            exhibit]


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


def _stdout_closed() -> bool:
    """Whether standard output is a pipe whose reader has gone (`info --json | head`): a flush
    fails with EPIPE, or (nothing left to flush) poll reports an error on the descriptor,
    which Linux does for a pipe with no reader."""
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        return True
    except (OSError, ValueError, AttributeError):
        return False
    try:
        poller = select.poll()
        poller.register(sys.stdout.fileno(), 0)
        return any(ev & select.POLLERR for _, ev in poller.poll(0))
    except (OSError, ValueError, AttributeError, io.UnsupportedOperation):
        return False


def _reader_left() -> int:
    """Ends quietly as Unix tools do when their reader leaves: what is still buffered goes to
    /dev/null (so the interpreter's last flush does not complain) and the exit status is
    128 + SIGPIPE = 141, what a shell reports for `cat` killed by SIGPIPE."""
    with contextlib.suppress(OSError, ValueError, AttributeError, io.UnsupportedOperation):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    return 128 + signal.SIGPIPE


def main(argv: list[str] | None = None) -> int:
    from .outputs import ignore_sigxfsz
    ignore_sigxfsz()  # past a file-size limit a write fails (EFBIG) and is reported, not fatal
    parser = build_parser()
    args = parser.parse_args(argv)  # argparse's --help ignores a closed pipe itself (exit 0)
    try:
        code = int(args.func(args) or 0)
        sys.stdout.flush()  # a reader that has gone shows here, not in the interpreter's exit
        return code
    except BrokenPipeError as e:  # stdout's reader gone: quiet; another pipe: an error
        if _stdout_closed():
            return _reader_left()
        print(f"gigascroll {args.command}: error: {_one_line(e)}", file=sys.stderr)
        return 2
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

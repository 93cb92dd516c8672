"""The `gigascroll` command line. Each subcommand lives in gigascroll.commands.<name>
and exposes `register(subparsers)`; the parser sets `func(args) -> int` on the namespace.
Errors the user can fix (bad files, bad parameters) print one line and exit with 2."""

from __future__ import annotations

import argparse
import sys

from .commands import bench, demo, export, info, pack, render, scenario, synth
from .errors import UserError

# Subcommand modules, in the order `gigascroll --help` lists them.
COMMANDS = [demo, synth, pack, info, export, bench, render, scenario]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="gigascroll",
        description="Gigapixel paintings in VR: virtual texturing and photon mapping.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for module in COMMANDS:
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (UserError, ValueError, OSError) as e:
        print(f"gigascroll {args.command}: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as e:  # SIGINT, or SIGTERM / SIGHUP during a build
        signum = getattr(e, "signum", 2)
        print(f"gigascroll {args.command}: interrupted{f' ({e})' if signum != 2 else ''}",
              file=sys.stderr)
        return 128 + signum

"""gimbal2axis: run scenes, sweeps, linearizations, frequency responses, comparison reports and the
master's benchmark on the Gimbal2Axis FMU. `gimbal2axis COMMAND --help` says more about each."""
from __future__ import annotations

import argparse
import sys

from ..version import __version__
from . import bench, freqresp, linearize, report, run, sweep, system

PROG = "gimbal2axis"
SUBCOMMANDS = {"run": run, "sweep": sweep, "linearize": linearize, "freqresp": freqresp, "report": report,
               "system": system, "bench": bench}
EXIT_USAGE = 2


class OneLineErrorParser(argparse.ArgumentParser):
    """Refuses bad arguments in one line on stderr, `gimbal2axis COMMAND: error: ...`, with exit status
    2: the usage is in --help, and a line is what a script calling the command can log."""

    def error(self, message: str):
        self.exit(EXIT_USAGE, f"{self.prog}: error: {' '.join(message.split())}\n")


def _wide_help(prog: str) -> argparse.HelpFormatter:
    return argparse.RawDescriptionHelpFormatter(prog, max_help_position=24)


def build_parser() -> OneLineErrorParser:
    parser = OneLineErrorParser(prog=PROG, description=__doc__, formatter_class=_wide_help)
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}",
                        help="print the package's version (the FMU's: CMakeLists.txt's project VERSION) and exit")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, module in SUBCOMMANDS.items():
        command = commands.add_parser(name, help=module.SUMMARY, description=module.__doc__,
                                      formatter_class=argparse.RawDescriptionHelpFormatter)
        module.add_arguments(command)
        command.set_defaults(execute=module.execute, command_parser=command)
    return parser


def main(argv: list[str] | None = None) -> int:
    args, unknown = build_parser().parse_known_args(sys.argv[1:] if argv is None else argv)
    if unknown:   # refused by the subcommand, which names itself (argparse would leave that to the top level)
        args.command_parser.error(f"unrecognized arguments: {' '.join(unknown)}")
    return args.execute(args)

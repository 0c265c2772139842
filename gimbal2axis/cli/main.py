"""gimbal2axis: run scenes, sweeps, linearizations, frequency responses, comparison reports and the
master's benchmark on the Gimbal2Axis FMU. `gimbal2axis COMMAND --help` says more about each.

Every subcommand ends with one of these exit statuses (its --help lists those it uses):
  0    done
  1    ran, but a requirement (run --check), a case (sweep), a check (bench) or the constraints (tune) failed
  2    refused: a bad argument, an input file, an output that cannot be written; nothing done
  3    run: failed part-way, the results up to the last good step kept, marked partial
  130  interrupted (SIGINT, Ctrl-C)
  143  run, sweep, tune: terminated (SIGTERM), what was finished kept"""
from __future__ import annotations

import argparse
import sys

from ..version import __version__
# The subcommands' modules import only the standard library at their top (their work's imports are
# inside their functions), so that --help and a refused argument answer at once.
from . import bench, freqresp, linearize, report, run, sweep, system, tune
from .failures import DEFAULT_EXIT_STATUSES, EXIT_ERROR, EXIT_INTERRUPTED, exit_status_help

PROG = "gimbal2axis"
SUBCOMMANDS = {"run": run, "sweep": sweep, "linearize": linearize, "freqresp": freqresp, "report": report,
               "system": system, "bench": bench, "tune": tune}
EXIT_USAGE = EXIT_ERROR


class OneLineErrorParser(argparse.ArgumentParser):
    """Refuses bad arguments in one line on stderr, `gimbal2axis COMMAND: error: ... (see gimbal2axis
    COMMAND --help)`, with exit status 2: the usage is in --help, and a line is what a script calling
    the command can log."""

    def error(self, message: str):
        self.exit(EXIT_USAGE, f"{self.prog}: error: {' '.join(message.split())} (see {self.prog} --help)\n")


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
        command.add_argument("--version", action="version", version=f"{PROG} {__version__}",
                             help="print the package's version and exit")
        module.add_arguments(command)
        statuses = exit_status_help(getattr(module, "EXIT_STATUSES", DEFAULT_EXIT_STATUSES))
        command.epilog = f"{command.epilog}\n\n{statuses}" if command.epilog else statuses
        command.set_defaults(execute=module.execute, command_parser=command)
    return parser


def main(argv: list[str] | None = None) -> int:
    args, unknown = build_parser().parse_known_args(sys.argv[1:] if argv is None else argv)
    if unknown:   # refused by the subcommand, which names itself (argparse would leave that to the top level)
        args.command_parser.error(f"unrecognized arguments: {' '.join(unknown)}")
    try:
        return args.execute(args)
    except KeyboardInterrupt:   # Ctrl-C where the subcommand does not handle it itself: no traceback
        print(f"\n{args.command_parser.prog}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED

"""How a command ends when its work fails: one line on stderr naming the command, and an exit
status, never a traceback for what the user can fix.

Exit statuses (the same meaning for every subcommand, each listing those it uses in its --help, built
by exit_status_help from the subcommand's EXIT_STATUSES, else DEFAULT_EXIT_STATUSES):
  0    done
  1    ran, but a requirement (run --check) or a case (sweep), a check (bench) failed
  2    refused: an argument, the scene, the output directory, a run that cannot fit; nothing done
  3    run: failed part-way (the FMU refused a step, the controller raised); what it recorded up
       to the last good step is written, marked partial
  130  interrupted (SIGINT, Ctrl-C: 128 + 2); a run keeps what it recorded, marked partial
  143  terminated (SIGTERM: 128 + 15); run and sweep keep what they finished
"""
from __future__ import annotations

import signal
import sys
from contextlib import contextmanager

from ..errors import SceneError, Terminated, one_line

EXIT_DONE, EXIT_FAILED_CHECK = 0, 1
EXIT_ERROR, EXIT_FAILED_PARTIAL, EXIT_INTERRUPTED, EXIT_TERMINATED = 2, 3, 130, 143
# What a subcommand without an EXIT_STATUSES of its own ends with.
DEFAULT_EXIT_STATUSES = {EXIT_DONE: "done",
                         EXIT_ERROR: "refused: an argument, an input file, or an output that cannot be written",
                         EXIT_INTERRUPTED: "interrupted (SIGINT, Ctrl-C)"}
# master.Stop.kind -> the exit status of a run that ended that way
EXIT_FOR_STOP = {"failed": EXIT_FAILED_PARTIAL, "interrupted": EXIT_INTERRUPTED, "terminated": EXIT_TERMINATED}


def exit_status_help(statuses: dict) -> str:
    """The `exit status:` block of a subcommand's --help: {status: meaning}, one entry each."""
    import textwrap

    return "exit status:\n" + "\n".join(
        textwrap.fill(meaning, 88, initial_indent=f"  {status:<5}", subsequent_indent=" " * 7)
        for status, meaning in sorted(statuses.items()))


def run_reporting_failures(prog: str, work) -> int:
    """work()'s exit status, or the status of its refusal (SceneError), of a file it could not write
    (OSError) or of Ctrl-C or SIGTERM, each said in one line."""
    try:
        return work()
    except SceneError as exc:
        print(one_line(f"{prog}: error: {exc}"), file=sys.stderr)
        return EXIT_ERROR
    except OSError as exc:   # writing the results (the directory was writable a moment ago)
        where = f"{exc.filename}: " if exc.filename else ""
        print(one_line(f"{prog}: error: {where}{exc.strerror or exc}"), file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Terminated:
        print(f"{prog}: terminated", file=sys.stderr)
        return EXIT_TERMINATED


SIGNAL_STOPS = {signal.SIGINT: ("interrupted", "interrupted by SIGINT (Ctrl-C)"),
                signal.SIGTERM: ("terminated", "terminated by SIGTERM")}


@contextmanager
def signals_end_the_run(stop):
    """While inside: SIGINT and SIGTERM go to `stop` (a master.StopRequest), which ends the run at its
    next step while it steps, so that what it recorded is written, and raises errors.Interrupted or
    Terminated in any other phase or on a repeated signal; the record is kept either way. The handlers
    before are restored on leaving."""
    def handle(signum, frame):
        stop.signal_received(*SIGNAL_STOPS[signum])

    previous = {signum: signal.signal(signum, handle) for signum in SIGNAL_STOPS}
    try:
        yield stop
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)

"""How a command ends when its work fails: one line on stderr naming the command, and an exit
status (2 refused or failed, 130 interrupted), never a traceback for what the user can fix."""
from __future__ import annotations

import sys

from ..errors import SceneError

EXIT_ERROR, EXIT_INTERRUPTED = 2, 130


def run_reporting_failures(prog: str, work) -> int:
    """work()'s exit status, or the status of its refusal (SceneError), of a file it could not write
    (OSError) or of Ctrl-C, each said in one line."""
    try:
        return work()
    except SceneError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except OSError as exc:   # writing the results (the directory was writable a moment ago)
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"{prog}: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED

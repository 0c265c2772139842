"""The co-simulation master: what a run is decided by before it starts (plan.py), the communication
loop on one FMU instance with its sensors, controller and the commands' delay (stepper.py, with the
compiled loop of compiled_loop.py for the built-in controllers, the only fast path), a run held in
memory (master.py) or streamed to disk chunk by chunk in bounded memory (streaming.py), many
user-controller scenes stepped together (lockstep.py), a run's signals and metrics (results.py), its
plots (plotting.py), and a scene file run to its CSV, Parquet and PNG (scene_files.py)."""
from .master import Plan, Stop, StopRequest, real_outputs, run
from .results import RunResult
from .scene_files import run_scene_file
from .streaming import run_streamed

__all__ = ["Plan", "RunResult", "Stop", "StopRequest", "real_outputs", "run", "run_scene_file", "run_streamed"]

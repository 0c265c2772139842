"""The `gimbal2axis` command: main.py reads the command line and hands it to the subcommand, one
module each (run, sweep, linearize, freqresp, report, system, bench), each with SUMMARY,
add_arguments(parser), execute(args) -> exit status and, when it ends otherwise than
failures.DEFAULT_EXIT_STATUSES says, EXIT_STATUSES (listed at the end of its --help). A subcommand's
module imports only the standard library and the package's leaves at its top, its work's modules
inside its functions: `gimbal2axis --help` builds every parser, and answers in a tenth of a second."""

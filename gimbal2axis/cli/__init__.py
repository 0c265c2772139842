"""The `gimbal2axis` command: main.py reads the command line and hands it to the subcommand, one
module each (run, sweep, linearize, freqresp, bench), each with SUMMARY, add_arguments(parser) and
execute(args) -> exit status."""

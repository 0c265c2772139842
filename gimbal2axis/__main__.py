"""`python -m gimbal2axis ...`: the same as the `gimbal2axis` command."""
import sys

from .cli.main import main

if __name__ == "__main__":
    sys.exit(main())

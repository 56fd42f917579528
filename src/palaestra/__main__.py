"""``python -m palaestra`` and the ``palaestra`` console script."""

import gc
import sys

from palaestra import cli

__all__ = ["main"]


def main() -> int:
    """Run the command line (``palaestra.cli.main``); the exit code."""
    code = cli.main()
    # The interpreter's final collection walks every torch object (0.4-2 s measured on a
    # 2-core machine): the command is done, so leave them to the process's exit.
    gc.freeze()
    return code


if __name__ == "__main__":
    sys.exit(main())

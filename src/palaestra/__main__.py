"""``python -m palaestra`` and the ``palaestra`` console script."""

import sys

from palaestra.cli import main

__all__ = ["main"]

if __name__ == "__main__":
    sys.exit(main())

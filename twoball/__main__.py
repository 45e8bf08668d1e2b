"""``python -m twoball``: the same as the ``twoball`` command."""

import sys

from twoball.cli import main

if __name__ == "__main__":
    sys.exit(main())

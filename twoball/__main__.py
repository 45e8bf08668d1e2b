"""``python -m twoball``: the same as the ``twoball`` command."""

import sys

from twoball.cli import main

sys.exit(main())

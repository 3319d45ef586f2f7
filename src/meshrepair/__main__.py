"""``python -m meshrepair``: the command-line tool, as the ``meshrepair`` script."""

import sys

from meshrepair.cli import main

if __name__ == "__main__":
    sys.exit(main())

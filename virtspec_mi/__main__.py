"""``python -m virtspec_mi``: the ``virtspec`` command line (:mod:`virtspec_mi.cli`)."""

import sys

from virtspec_mi.cli import main

if __name__ == "__main__":
    sys.exit(main())

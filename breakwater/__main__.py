"""``python -m breakwater``: the command line (see :mod:`breakwater.cli`)."""

from __future__ import annotations

import sys

from breakwater.cli import main

if __name__ == "__main__":
    sys.exit(main())

"""``python -m utamp_gym.suites.procedural select|digest|check`` (see `selection.main`)."""

import sys

from utamp_gym.suites.procedural.selection import main

if __name__ == "__main__":
    sys.exit(main())

"""``python -m utamp_gym.suites.procedural_v2 select|write|check`` (`selection.main`)."""

import sys

from utamp_gym.suites.procedural_v2.selection import main

if __name__ == "__main__":
    sys.exit(main())

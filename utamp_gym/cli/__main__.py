"""``python -m utamp_gym.cli``: the `utamp` command."""

import sys

from utamp_gym.cli import main

if __name__ == "__main__":
    sys.exit(main())

"""``python -m mmusv``: the ``mmusv`` command (:func:`mmusv.cli.main`), for environments without the console
script on their path."""

import sys

from mmusv.cli import main

if __name__ == "__main__":
    sys.exit(main())

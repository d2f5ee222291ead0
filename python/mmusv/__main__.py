"""``python -m mmusv``: the ``mmusv`` command (:func:`mmusv._launch.main`), for environments without the console
script on their path."""

import sys

from mmusv._launch import main

if __name__ == "__main__":
    sys.exit(main())

"""``python -m benchmarks.mutation``: see :mod:`benchmarks.mutation.cli`."""

import sys

from benchmarks.mutation.cli import main

if __name__ == "__main__":
    sys.exit(main())

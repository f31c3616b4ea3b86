"""``python -m benchmarks.robustness --out DIR [--timeout S] [--only api|cli] [--match TEXT]``."""

from benchmarks.robustness.cli import main

raise SystemExit(main())

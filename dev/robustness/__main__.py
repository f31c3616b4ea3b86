"""``python -m dev.robustness --out DIR [--timeout S] [--only api|cli] [--match TEXT]``."""

from dev.robustness.cli import main

if __name__ == "__main__":
    raise SystemExit(main())

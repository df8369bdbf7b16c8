"""Entry point of the ``broachkit`` command (placeholder until the engine demo lands)."""

from __future__ import annotations

import argparse
import sys


def main(argv: list[str] | None = None) -> int:
    """Run the ``broachkit`` command line; returns the exit code."""
    parser = argparse.ArgumentParser(prog="broachkit")
    parser.parse_args(argv)
    sys.stdout.write("broachkit: nothing to run yet\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""``python -m app [demo|render|edit|send|receive] ...`` — the program's entry point."""

from __future__ import annotations

import sys


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    from app.cli import run

    return run(argv)


if __name__ == "__main__":
    sys.exit(main())

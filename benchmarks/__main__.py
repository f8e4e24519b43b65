"""``python -m benchmarks [--quick] [--only NAME ...]``: print every speed and accuracy table."""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse
import importlib
import pkgutil
import sys
import time
import traceback
from pathlib import Path

from benchmarks.harness import Context, host_speed, libraries, machine, pin_one_core, registered


def _load_all() -> None:
    here = Path(__file__).parent
    for mod in sorted(pkgutil.iter_modules([str(here)]), key=lambda m: m.name):
        if mod.name.startswith("bench_"):
            importlib.import_module(f"benchmarks.{mod.name}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__)
    ap.add_argument("--quick", action="store_true", help="few runs, small inputs (a smoke test)")
    ap.add_argument("--only", nargs="*", default=None, help="run only benchmarks whose name contains one of these")
    args = ap.parse_args(argv)
    _load_all()
    pinned = pin_one_core()
    print(f"# Inkface benchmarks\nmachine: {machine()}; {pinned}; {'quick' if args.quick else 'full'} run\n"
          f"libraries: {libraries()}\nhost speed: 10⁶ Python additions in {host_speed():.0f} ms (a yardstick for "
          "comparing hosts: the per-frame times scale with it)\n")
    ctx = Context(quick=args.quick)
    failed = 0
    for name, fn in registered():
        if args.only and not any(o in name for o in args.only):
            continue
        t0 = time.perf_counter()
        try:
            tables = fn(ctx)
        except Exception:
            failed += 1
            print(f"## {name}: FAILED\n{traceback.format_exc()}", file=sys.stderr)
            continue
        if not isinstance(tables, (list, tuple)):
            tables = [tables]
        for t in tables:
            print(t.render())
            print()
        print(f"({name}: {time.perf_counter() - t0:.1f} s)\n")
        sys.stdout.flush()
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

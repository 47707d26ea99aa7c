"""``python -m skyfall._demo --out out``: the demo (what ``make demo`` and ``skyfall demo`` run)."""

from skyfall._demo import main

if __name__ == "__main__":  # importing the module (the doctests walk the package) runs nothing
    raise SystemExit(main())

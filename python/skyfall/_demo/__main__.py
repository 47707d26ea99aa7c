"""``python -m skyfall._demo --out out``: the demo (what ``make demo`` and ``skyfall demo`` run)."""

from skyfall._demo import main

raise SystemExit(main())

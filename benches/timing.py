"""Timing shared by the benchmarks."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable


def median_s(fn: Callable[[], object], repeat: int = 7) -> float:
    """Median wall time of ``repeat`` calls after one warm-up call, seconds."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def block_times_s(fns: dict[str, Callable[[], object]], blocks: int = 5, per_block: int = 5) -> dict[str, list[float]]:
    """Per function, the median wall time of each block, seconds, timed in alternating blocks:
    every round times ``per_block`` calls of each function in turn, so a slow spell of a
    shared machine weighs on all of them alike, and ratios can be taken round by round. Each
    block starts after a 50 ms pause and one untimed call: a library's worker threads (OpenCV's,
    rayon's) spin for a while after its last call and would otherwise take cores from the next
    function's first calls."""
    out: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(blocks):
        for k, fn in fns.items():
            time.sleep(0.05)  # then median_s's own untimed call
            out[k].append(median_s(fn, per_block))
    return out

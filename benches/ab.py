"""A/B of the bench rows: a base commit's skyfall against the working tree's, timed alternately in
one run. Writes benches/results/ab.md and ab.json. Run with `make bench-ab BASE=<rev>` (default
HEAD~1).

The project's rule is that no change makes a bench row slower beyond noise without saying so and
why; on a shared machine two `make bench` runs an hour apart differ by more than most changes, so
this compares the two versions in the same minutes:

- BASE's wheel is built once (maturin, in a detached worktree under /tmp, with its own cargo target
  dir) and installed into its own venv, both cached by commit hash under `.ab-cache/` (ignored by
  git). `--base-wheel` installs a wheel you already have instead of building; `--base-python` uses
  an interpreter that already has BASE's skyfall.
- HEAD is the skyfall of the running interpreter (`make bench-ab` uses .venv, which `make build`
  builds from the working tree, committed or not: ab.md records HEAD's hash and whether the tree was
  dirty).
- --procs worker processes per version (this file with `--worker`, so both run the same row code:
  the set-up functions of benches/bench_*.py), one pair per round in turn: a process's memory
  layout can bias a memory-bound row for its whole life (an A/A run with one process each called
  the 8-bit haze row 18 % slower), so the processes' spread lands in the band. Each round times
  every row once per version, in turn, the two versions' order swapped every round; a worker
  times a block of n calls (n chosen from the row's second call, about 0.25 s a block, 1-20
  calls) after a 50 ms pause and an untimed call, and reports the block's median. The other
  workers wait idle meanwhile. Default 13-15 rounds, about 6-7 minutes with BASE cached (building
  BASE's wheel first adds about 3 minutes on a 2-CPU machine).
- Per row: base and head medians over rounds, and the per-round ratio head/base, summarised by
  its median and 10-90 % range (the noise band). Verdict: "slower" when the whole band lies
  above 1 and the median ratio is at least 1 + MIN_EFFECT; "faster" when the whole band lies below
  1 and the median at most 1 - MIN_EFFECT; otherwise "within noise". A row whose set-up fails on
  one version (API added since) is listed as "head only" (or "base only").
- Rows slower than SLOW_S a call run in the first --slow-rounds rounds only, and rounds stop early
  (never below --min-rounds) when the next would end past --budget-s of timing.

Rows: every timed skyfall row of benches/bench_*.py (not the peers'/numpy's rows, which do not
depend on skyfall's version), plus the demo's 1280x720 rainy street frame.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # as in bench_rain: idle BLAS threads only add noise

import argparse
import json
import platform
import shutil
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

BENCHES = Path(__file__).resolve().parent
ROOT = BENCHES.parent
RESULTS = BENCHES / "results"
CACHE = ROOT / ".ab-cache"
MIN_EFFECT = 0.02  # a median ratio within 2 % of 1 is never called slower or faster
SLOW_S = 0.4  # s per call: rows slower than this run in fewer rounds
BLOCK_S = 0.25  # s: the target length of one timed block
MAX_CALLS = 20  # calls in a block, at most


# --------------------------------------------------------------------------------------------
# The rows (built in each worker, from the benches' own set-up functions)


def make_rows() -> dict[str, tuple[str, Callable[[], Callable[[], object]]]]:
    """name -> (description, factory); a factory builds the row's set-up and returns the call to
    time. Factories run in the worker, against whichever skyfall it imports."""
    import bench_physics
    import bench_rain
    import bench_render
    import bench_sky

    from skyfall import Renderer, Weather, physics, rain, scenes, sky

    cache: dict[str, Any] = {}

    def once(key: str, fn: Callable[[], Any]) -> Any:
        if key not in cache:
            cache[key] = fn()
        return cache[key]

    def cpu1080() -> Renderer:
        return once("cpu1080", lambda: Renderer(bench_rain.W, bench_rain.H, backend="cpu"))

    def gpu1080() -> Renderer:
        return once("gpu1080", lambda: Renderer(bench_rain.W, bench_rain.H, backend="gpu"))

    def photo() -> Any:
        return once("photo", lambda: bench_rain.street_photo(cpu1080()))

    def photo_rows() -> dict[str, Callable[[], object]]:
        return once("photo_rows", lambda: bench_rain.photo_rows(cpu1080(), photo()))

    def haze() -> Any:
        return once("haze", bench_render.haze_photo)

    def street() -> Any:
        return once("street", scenes.street)

    rows: dict[str, tuple[str, Callable[[], Callable[[], object]]]] = {}
    d = once("d", lambda: bench_physics.diameters(1_000_000))
    for model in ("beard", "sphere", "atlas"):
        rows[f"physics.terminal_velocity.{model}"] = (
            f"physics: terminal_velocity, 1M diameters, {model}",
            lambda m=model: lambda: physics.terminal_velocity(d, model=m),
        )
    for size in bench_physics.TEXTURE_SIZES:
        rows[f"physics.textures.{size}"] = (
            f"physics: rain.textures, Yoshida, Dobashi & Yamamoto's 4x6 grid at {size}²",
            lambda s=size: lambda: rain.textures(rain.SEED_RAIN_RATES_MM_H, rain.SEED_DIAMETERS_MM, size_px=s, seed=0),
        )
    rows["render.haze.cpu"] = ("render: haze only, 1080p float photo, CPU", lambda: lambda: cpu1080().render(haze()[2], haze()[3]))
    rows["render.street.cpu"] = ("render: street 1080p, ray cast + haze, CPU", lambda: lambda: cpu1080().render(street(), haze()[3]))
    rows["render.haze.gpu"] = ("render: haze only, 1080p float photo, GPU incl. upload + readback", lambda: lambda: gpu1080().render(haze()[2], haze()[3]))
    rows["render.street.gpu"] = ("render: street 1080p, ray cast + haze, GPU incl. readback", lambda: lambda: gpu1080().render(street(), haze()[3]))
    photo_desc = {
        "fused": "render_srgb8, billboards + haze (fused 8-bit)",
        "fused_drops": "render_srgb8, drops method",
        "fused_out": "render_srgb8 into a reused out= array",
        "haze": "render_srgb8, haze only",
        "float_u8": "render (float) + io.to_srgb8",
        "float": "render, float32 in and out",
        "float_out": "render into a previous frame's arrays (out=)",
    }
    for key, desc in photo_desc.items():
        rows[f"rain.{key}"] = (f"rain: 1080p street photo 10 mm/h, {desc}, CPU", lambda k=key: photo_rows()[k])
    rows["rain.gpu"] = (
        "rain: 1080p street photo 10 mm/h, billboards + haze, float, GPU incl. upload + readback",
        lambda: lambda: gpu1080().render(photo().scene(), photo().weather),
    )

    def street720() -> Callable[[], object]:
        r, s, w = Renderer(1280, 720, backend="cpu"), scenes.street(), Weather(rain_rate_mm_h=10.0)
        return lambda: r.render(s, w)

    rows["demo.street720"] = ("demo: street box scene 1280x720, 10 mm/h rain (streaks + haze), CPU", street720)
    pts = once("pts", bench_sky.street_points)
    for n in bench_sky.SAMPLES:
        rows[f"sky.points.{n}"] = (f"sky: horizontal_illuminance, 1000 street points, {n} azimuths", lambda n=n: lambda: sky.horizontal_illuminance(pts, street(), samples=n))
    def fresh(fn: Callable[[], object]) -> Callable[[], object]:
        """fn with sky's per-process map cache emptied first: every call builds its map, as the
        single timed build or first frame of bench_sky does (a repeated call would time a hit)."""

        def call() -> object:
            sky._cache.clear()
            return fn()

        return call

    for spacing in bench_sky.MAP_SPACINGS:
        rows[f"sky.map.{spacing:g}"] = (f"sky: ambient_light_map build over the street, {spacing:g} m", lambda s=spacing: fresh(lambda: bench_sky.street_map(street(), s)))

    def frame(spacing: float, first: bool) -> Callable[[], object]:
        r, w = bench_sky.frame_setup()
        fn = lambda: r.render(street(), w, ambient_spacing_m=spacing * 1.0001)  # noqa: E731
        return fresh(fn) if first else fn

    for spacing in bench_sky.FRAME_SPACINGS:
        rows[f"sky.frame.{spacing:g}.first"] = (f"sky: 640x360 rainy street, {spacing:g} m map built in the frame", lambda s=spacing: frame(s, True))
        rows[f"sky.frame.{spacing:g}.cached"] = (f"sky: 640x360 rainy street, {spacing:g} m map cached", lambda s=spacing: frame(s, False))
    return rows


def worker() -> None:
    """Answer JSON lines on stdin: {"cmd": "setup"} builds every row, calls it once and times a second call;
    {"cmd": "time", "row": name, "n": n} times a block and answers its median, seconds."""
    proto = sys.stdout
    sys.stdout = sys.stderr  # anything the package prints stays off the protocol
    import skyfall

    fns: dict[str, Callable[[], object]] = {}
    for line in sys.stdin:
        msg = json.loads(line)
        if msg["cmd"] == "setup":
            info: dict[str, Any] = {"skyfall": str(Path(skyfall.__file__).parent), "rows": {}}
            for name, (_, factory) in make_rows().items():
                if name not in msg["rows"]:
                    continue
                try:
                    fn = factory()
                    fn()  # one-off costs: a map built, shaders compiled, buffers grown
                    t0 = time.perf_counter()
                    fn()
                    info["rows"][name] = {"ok": True, "second_s": time.perf_counter() - t0}
                    fns[name] = fn
                except Exception as exc:  # noqa: BLE001 - an API the version lacks, no GPU, ...
                    info["rows"][name] = {"ok": False, "error": f"{type(exc).__name__}: {exc}"[:300]}
            answer: dict[str, Any] = info
        else:
            fn = fns[msg["row"]]
            time.sleep(0.05)  # a previous call's worker threads (rayon's, the other version's) wind down
            if msg.get("warm", True):
                fn()
            times = []
            for _ in range(msg["n"]):
                t0 = time.perf_counter()
                fn()
                times.append(time.perf_counter() - t0)
            answer = {"s": statistics.median(times)}
        proto.write(json.dumps(answer) + "\n")
        proto.flush()


class Worker:
    def __init__(self, python: str, label: str) -> None:
        self.label = label
        env = dict(os.environ)
        env.pop("PYTHONPATH", None)
        env.pop("VIRTUAL_ENV", None)
        self.proc = subprocess.Popen(
            [python, str(Path(__file__).resolve()), "--worker"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, cwd=BENCHES, env=env
        )

    def ask(self, **msg: Any) -> Any:
        assert self.proc.stdin and self.proc.stdout
        self.proc.stdin.write(json.dumps(msg) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError(f"{self.label} worker died (exit {self.proc.wait()})")
        return json.loads(line)

    def close(self) -> None:
        if self.proc.stdin:
            self.proc.stdin.close()
        self.proc.wait(timeout=60)


# --------------------------------------------------------------------------------------------
# The base version's venv


def git(*args: str) -> str:
    return subprocess.run(["git", *args], cwd=ROOT, check=True, capture_output=True, text=True).stdout.strip()


def pins(*names: str) -> list[str]:
    """Pinned requirements from requirements-dev.txt for the given packages."""
    out = []
    for line in (ROOT / "requirements-dev.txt").read_text().splitlines():
        name = line.split("==")[0].strip().lower()
        if name in names:
            out.append(line.strip())
    return out


def base_python(commit: str, wheel: str | None) -> str:
    """The interpreter of BASE's cached venv, building BASE's wheel and the venv if needed."""
    cache = CACHE / commit
    py = cache / "venv" / "bin" / "python"
    if (cache / "ready").exists() and py.exists():
        print(f"base {commit[:10]}: reusing {cache}", file=sys.stderr)
        return str(py)
    wheels = cache / "wheel"
    if wheel is None:
        shutil.rmtree(wheels, ignore_errors=True)
        wt = Path(f"/tmp/ab-base-{commit[:12]}")
        if not wt.exists():
            git("worktree", "add", "--detach", str(wt), commit)
        try:
            env = dict(os.environ, PYO3_PYTHON=sys.executable, CARGO_TARGET_DIR=str(CACHE / "target"))
            maturin = Path(sys.executable).parent / "maturin"
            print(f"base {commit[:10]}: building its wheel in {wt} (cached after this)", file=sys.stderr)
            subprocess.run([str(maturin), "build", "--release", "--locked", "-q", "-o", str(wheels)], cwd=wt, env=env, check=True)
        finally:
            git("worktree", "remove", "--force", str(wt))
        wheel = str(next(wheels.glob("skyfall-*.whl")))
    shutil.rmtree(cache / "venv", ignore_errors=True)
    subprocess.run(["python3", "-m", "venv", str(cache / "venv")], check=True)
    subprocess.run([str(py), "-m", "pip", "install", "-q", wheel, *pins("numpy", "tqdm")], check=True)
    (cache / "ready").write_text(f"{wheel}\n")
    return str(py)


# --------------------------------------------------------------------------------------------
# The run


def band(ratios: list[float]) -> tuple[float, float, float]:
    q = np.quantile(ratios, [0.1, 0.5, 0.9])
    return float(q[1]), float(q[0]), float(q[2])


def verdict(median: float, lo: float, hi: float) -> str:
    if lo > 1 and median >= 1 + MIN_EFFECT:
        return "slower"
    if hi < 1 and median <= 1 - MIN_EFFECT:
        return "faster"
    return "within noise"


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "?"


def fmt_ms(s: float) -> str:
    return f"{s * 1e3:.1f} ms" if s < 1 else f"{s:.2f} s"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--base", default="HEAD~1", help="the base revision (default HEAD~1)")
    ap.add_argument("--base-wheel", help="install this wheel (of BASE) instead of building one")
    ap.add_argument("--base-python", help="an interpreter that already has BASE's skyfall (skips the cache)")
    ap.add_argument("--rounds", type=int, default=15, help="at most this many rounds (default 15)")
    ap.add_argument("--min-rounds", type=int, default=7, help="at least this many, whatever the budget (default 7)")
    ap.add_argument("--slow-rounds", type=int, default=6, help=f"rounds of the rows slower than {SLOW_S} s (default 6: each of 3 process pairs in both orders)")
    ap.add_argument("--budget-s", type=float, default=360.0, help="seconds of timing after set-up (default 360)")
    ap.add_argument("--procs", type=int, default=3, help="worker processes per version, taking turns by round (default 3)")
    ap.add_argument("--rows", help="only rows whose name contains one of these comma-separated strings")
    ap.add_argument("--out", default=str(RESULTS), help="where ab.md and ab.json go (default benches/results)")
    args = ap.parse_args()
    if args.worker:
        return worker()

    t_start = time.perf_counter()
    commit = git("rev-parse", "--verify", f"{args.base}^{{commit}}")
    head = git("rev-parse", "HEAD")
    dirty = bool(git("status", "--porcelain", "--untracked-files=no"))
    py_base = args.base_python or base_python(commit, args.base_wheel)
    load0 = os.getloadavg()
    # Several processes per version, taking turns round by round: a process's memory layout
    # (ASLR, the alignment of its frame buffers) can bias a memory-bound row by 10-20 % for its
    # whole life, which alternation alone does not remove (an A/A run showed it), so it has to
    # show as round-to-round noise instead.
    bases = [Worker(py_base, "base") for _ in range(args.procs)]
    heads = [Worker(sys.executable, "head") for _ in range(args.procs)]
    rows = make_rows()  # for the descriptions (and the order)
    names = [n for n in rows if not args.rows or any(s in n for s in args.rows.split(","))]
    setups = {"base": [w.ask(cmd="setup", rows=names) for w in bases], "head": [w.ask(cmd="setup", rows=names) for w in heads]}
    info = {k: v[0] for k, v in setups.items()}
    for k, v in setups.items():  # a row counts as runnable when it ran in every process; its cost is the slowest's
        for n in names:
            rs = [x["rows"][n] for x in v]
            info[k]["rows"][n] = {"ok": all(r["ok"] for r in rs), "second_s": max(r.get("second_s", 0.0) for r in rs), "error": next((r["error"] for r in rs if not r["ok"]), None)}
    t_setup = time.perf_counter() - t_start
    both = [n for n in names if info["base"]["rows"][n]["ok"] and info["head"]["rows"][n]["ok"]]
    # A row's cost: the slower version's second call (after one for one-off costs).
    first = {n: max(info["base"]["rows"][n]["second_s"], info["head"]["rows"][n]["second_s"]) for n in both}
    per_block = {n: max(1, min(MAX_CALLS, round(BLOCK_S / first[n]))) for n in both}
    slow = {n for n in both if first[n] > SLOW_S}
    times: dict[str, dict[str, list[float]]] = {n: {"base": [], "head": []} for n in both}
    t0 = time.perf_counter()
    rounds = 0
    round_s: list[float] = []
    while rounds < args.rounds:
        elapsed = time.perf_counter() - t0
        if rounds >= args.min_rounds and round_s and elapsed + max(round_s[-2:]) > args.budget_s:
            break
        tr = time.perf_counter()
        base, headw = bases[rounds % args.procs], heads[rounds % args.procs]
        # The order flips every round (and every cycle of processes too, when there is an even
        # number of them), so every pair of processes meets both orders.
        flip = rounds % 2 ^ ((rounds // args.procs) % 2 if args.procs % 2 == 0 else 0)
        order = [headw, base] if flip else [base, headw]
        for n in both:
            if n in slow and rounds >= args.slow_rounds:
                continue
            for w in order:
                times[n][w.label].append(w.ask(cmd="time", row=n, n=per_block[n], warm=n not in slow)["s"])
        rounds += 1
        round_s.append(time.perf_counter() - tr)
        print(f"round {rounds}: {round_s[-1]:.0f} s", file=sys.stderr)
    for w in bases + heads:
        w.close()
    load1 = os.getloadavg()

    results = []
    for n in names:
        r: dict[str, Any] = {"row": n, "what": rows[n][0]}
        if n in both:
            b, h = times[n]["base"], times[n]["head"]
            med, lo, hi = band([y / x for x, y in zip(b, h)])
            r |= {"base_s": statistics.median(b), "head_s": statistics.median(h), "ratio": med, "ratio_p10": lo, "ratio_p90": hi}
            r |= {"rounds": len(b), "calls_per_block": per_block[n], "verdict": verdict(med, lo, hi), "base_rounds_s": b, "head_rounds_s": h}
        else:
            ok_b, ok_h = info["base"]["rows"][n]["ok"], info["head"]["rows"][n]["ok"]
            r["verdict"] = "head only" if ok_h else "base only" if ok_b else "neither"
            r["errors"] = {k: info[k]["rows"][n].get("error") for k in ("base", "head") if not info[k]["rows"][n]["ok"]}
        results.append(r)

    env = {
        "cpus": os.cpu_count(),
        "cpu": cpu_model(),
        "machine": platform.machine(),
        "python": platform.python_version(),
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "load_avg_1_5_15_start": load0,
        "load_avg_1_5_15_end": load1,
    }
    meta = {
        "base": commit,
        "base_subject": git("log", "-1", "--format=%s", commit),
        "head": head,
        "head_dirty": dirty,
        "base_skyfall": info["base"]["skyfall"],
        "head_skyfall": info["head"]["skyfall"],
        "rounds": rounds,
        "procs_per_version": args.procs,
        "setup_s": t_setup,
        "timing_s": time.perf_counter() - t0,
        "min_effect": MIN_EFFECT,
        "slow_s": SLOW_S,
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "ab.json").write_text(json.dumps({"env": env, "meta": meta, "rows": results}, indent=2) + "\n")
    slow_n = min(rounds, args.slow_rounds)
    lines = [
        f"# A/B: {commit[:10]} (base) against {head[:10]}{' + uncommitted changes' if dirty else ''} (head)",
        "",
        f"{env['date']}, {env['cpus']} CPUs ({env['cpu']}, {env['machine']}), Python {env['python']}. Written by",
        f"`make bench-ab BASE={args.base}` (benches/ab.py). The machine is shared: other processes may run during",
        f"the A/B (load average {load0[0]:.1f} at the start, {load1[0]:.1f} at the end), which is why the two",
        "versions are timed alternately in one run rather than compared across runs.",
        "",
        f"Base: `{commit[:10]}` {meta['base_subject']}",
        "",
        f"Each row was timed in {rounds} rounds ({slow_n} for rows over {SLOW_S:g} s a call); in each round each version",
        f"(one of its {args.procs} worker processes, in turn) timed a block of 1-20 calls after a 50 ms pause and an untimed call (rows over",
        f"{SLOW_S:g} s: no untimed call), the versions' order swapped every round. Times: medians over rounds of each",
        "block's median (each version's own; they move with the machine's load, so read the ratio, which pairs the",
        "versions round by round). Ratio: head/base per round, its median and, in brackets, its 10-90 % range over rounds",
        f"(the noise band). Verdict: **slower** when the whole band is above 1 and the median ratio ≥ {1 + MIN_EFFECT:.2f};",
        f"**faster** when the whole band is below 1 and the median ≤ {1 - MIN_EFFECT:.2f}; otherwise within noise.",
        "",
        "| row | base | head | head/base [10–90 %] | verdict |",
        "|---|---|---|---|---|",
    ]
    for r in results:
        if "ratio" in r:
            v = r["verdict"] if r["verdict"] == "within noise" else f"**{r['verdict']}**"
            lines.append(
                f"| {r['what']} | {fmt_ms(r['base_s'])} | {fmt_ms(r['head_s'])} | {r['ratio']:.3f} [{r['ratio_p10']:.3f}–{r['ratio_p90']:.3f}] | {v} |"
            )
    only = [r for r in results if "ratio" not in r]
    if only:
        lines += ["", "Not compared:", ""]
        for r in only:
            why = "; ".join(f"{k}: {e}" for k, e in r["errors"].items())
            lines.append(f"- {r['what']}: {r['verdict']} ({why})")
    lines += [
        "",
        f"Set-up (workers, scenes, first calls) {t_setup:.0f} s, timing {meta['timing_s']:.0f} s. Per-round times in ab.json.",
    ]
    (out / "ab.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

"""A dataset run: :func:`generate` (the items, those to make, run in this process, in spawned
worker processes or on a Dask cluster), the progress and the manifest (see :mod:`skyfall.dataset`)."""

from __future__ import annotations

import json
import os
import signal
import sys
import threading
import time
from collections.abc import Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from multiprocessing import get_context
from pathlib import Path
from typing import Any

from tqdm import tqdm  # type: ignore[import-untyped]

import skyfall
from skyfall.dataset.io import atomic_write, find_depth, list_images, remove_temporaries, write_json
from skyfall.dataset.item import COSTS, ItemSource, Worker, item_name, render_items, verify_item
from skyfall.dataset.sample import DatasetConfig, sample_item

__all__ = ["DatasetConfig", "Summary", "generate", "sample_item", "sources"]


@dataclass
class Summary:
    """What a run did.

    Attributes
    ----------
    items : int
        Items in the run (those of ``indices`` when given).
    generated, skipped, errors : int
        Items rendered now and complete, kept by ``resume`` (complete and intact), and
        recorded as errors (an error is not counted as generated). An interrupted run counts
        what its rows on disk say: every item finished before it stopped (those in flight
        included), none more.
    interrupted : bool
        Stopped by Ctrl-C (the items done are complete; resume to finish).
    seconds : float
        Wall time, s.
    first_to_last_s : float
        Time from the first item's completion to the last's, s (see ``steady_items_per_s``).
    cost_s : dict of str to float
        Summed per-item cost of the generated items, s, by part (see
        :data:`skyfall.dataset.item.COSTS`): read, render, encode, write.
    workers : int
        Worker processes.
    """

    items: int = 0
    generated: int = 0
    skipped: int = 0
    errors: int = 0
    interrupted: bool = False
    seconds: float = 0.0
    cost_s: dict[str, float] = field(default_factory=lambda: dict.fromkeys(COSTS, 0.0))
    workers: int = 1
    error_messages: list[str] = field(default_factory=list)
    first_to_last_s: float = 0.0

    @property
    def items_per_s(self) -> float:
        """Items generated per second of wall time (the workers' start included)."""
        return self.generated / self.seconds if self.seconds > 0 else 0.0

    @property
    def steady_items_per_s(self) -> float:
        """Items per second between the first item's completion and the last's: the rate once
        the workers are up (their start, about a second per process, left out)."""
        return (self.generated - 1) / self.first_to_last_s if self.first_to_last_s > 0 else 0.0

    def __str__(self) -> str:
        cost = ", ".join(f"{k} {1e3 * v / max(self.generated, 1):.1f}" for k, v in self.cost_s.items())
        head = "interrupted: " if self.interrupted else ""
        return (
            f"{head}{self.items} items: {self.generated} generated, {self.skipped} kept, {self.errors} errors; "
            f"{self.seconds:.1f} s, {self.items_per_s:.2f} items/s on {self.workers} worker(s); per item ms: {cost}"
        )


def sources(config: DatasetConfig) -> list[ItemSource]:
    """The run's items in index order: each photo's ``variants`` (photo k, variant v is item
    k * variants + v), or the scene's.

    Raises
    ------
    FileNotFoundError
        When ``input`` or ``depth`` is not a folder.
    ValueError
        When ``input`` holds no photo.
    """
    if config.input is None:
        return [ItemSource(i) for i in range(config.variants)]
    images = list_images(config.input)
    if not images:
        raise ValueError(f"input = {str(config.input)!r} holds no image file ({', '.join(sorted(e[1:] for e in _exts()))})")
    folder = config.depth if isinstance(config.depth, Path) else None
    if folder is not None and not folder.is_dir():
        raise FileNotFoundError(f"depth = {str(folder)!r} is not a folder")
    out = []
    for k, image in enumerate(images):
        depth = find_depth(folder, image.stem) if folder is not None else None
        missing = folder is not None and depth is None
        out += [ItemSource(k * config.variants + v, image, depth, missing) for v in range(config.variants)]
    return out


def _exts() -> frozenset[str]:
    from skyfall.dataset.io import IMAGE_EXTENSIONS

    return IMAGE_EXTENSIONS


# One per worker process: its renderers and caches (made by _init_worker).
_WORKER: Worker | None = None


def _end_with_parent(parent: int) -> None:
    """Make this worker process end when its parent dies, however it dies (``kill -9``
    included, which runs none of the parent's clean-up): on Linux the kernel's parent-death
    signal (``prctl(PR_SET_PDEATHSIG, SIGKILL)``), elsewhere a thread that watches the parent's
    pid. A worker's item in flight is written atomically, so ending it anywhere is safe; with
    the workers gone the multiprocessing resource tracker ends too (its pipe closes)."""
    armed = False
    if sys.platform.startswith("linux"):
        import ctypes

        try:
            libc = ctypes.CDLL(None, use_errno=True)
            pr_set_pdeathsig = 1
            armed = libc.prctl(pr_set_pdeathsig, int(signal.SIGKILL), 0, 0, 0) == 0
        except (OSError, AttributeError):
            armed = False
    if os.getppid() != parent:  # the parent died before the signal was armed
        os._exit(1)
    if armed:
        return

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, name="skyfall-parent-watch", daemon=True).start()


def _init_worker(config: DatasetConfig, threads: int | None, parent: int | None = None) -> None:
    """A worker process's start: it ends when its parent does (:func:`_end_with_parent`),
    Ctrl-C is the main process's to handle (it lets the items in flight finish), and the
    renderer's thread pool is sized before its first frame."""
    global _WORKER
    if parent is not None:
        _end_with_parent(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if threads is not None:
        os.environ["RAYON_NUM_THREADS"] = str(threads)
    _WORKER = Worker(config)


def _work(chunk: list[ItemSource]) -> list[tuple[dict[str, Any], dict[str, float]]]:
    """A chunk of items in a worker process: each written while the next renders."""
    assert _WORKER is not None
    return list(render_items(_WORKER, chunk))


CHUNK_ITEMS = 4
"""Items per task of a worker process, at most: within a chunk each item's encoding and writing
overlap the next one's rendering (:func:`skyfall.dataset.item.render_items`), so 3 of 4 do."""


def _chunks(todo: list[ItemSource], workers: int) -> list[list[ItemSource]]:
    """``todo`` in chunks of at most :data:`CHUNK_ITEMS`, small enough that each worker gets
    two at least (the last items do not wait on one busy worker)."""
    size = max(1, min(CHUNK_ITEMS, len(todo) // (2 * workers)))
    return [todo[i : i + size] for i in range(0, len(todo), size)]


def generate(
    config: DatasetConfig | None = None,
    *,
    workers: int = 1,
    threads_per_worker: int | None = None,
    resume: bool = False,
    indices: Iterable[int] | None = None,
    progress: bool = True,
    scheduler: Any = None,
    **options: Any,
) -> Summary:
    """Generate a dataset (see the module docstring for what it writes).

    Parameters
    ----------
    config : DatasetConfig, optional
        The options; or give them as keywords (``out=``, ``input=`` or ``scene=``,
        ``variants=``, ``seed=``, ranges such as ``rain_rate_mm_h="1:50"``: every field of
        :class:`~skyfall.dataset.sample.DatasetConfig`).
    workers : int
        Worker processes, in [1, 256], each holding its own renderer made once. 1 (without
        ``threads_per_worker``) renders in this process. The bytes written do not depend on it.
    threads_per_worker : int, optional
        The CPU renderer's threads in each worker process; default: the cores shared out
        (os.cpu_count() // workers, at least 1) when workers > 1, all of them for 1. Given, the
        items are rendered in worker processes even for ``workers=1``.
    resume : bool
        Keep the items already complete (their row and every file's sha256 intact, for the
        same options) and generate the rest. False regenerates every item.
    indices : iterable of int, optional
        Only these items (e.g. one regenerated alone); the manifest is then left as it is.
    progress : bool
        Show a tqdm progress bar (items/s and the time left).
    scheduler : str or dask.distributed.Client, optional
        Render through Dask distributed instead of local processes: a scheduler's address
        (``"tcp://host:8786"``) or a connected ``Client``. Each Dask worker thread keeps its
        own renderer; the workers write the files themselves, so ``out`` (and the inputs) must be
        on a file system they all see, at the same path. The bytes are those of a local run.
        ``workers`` and ``threads_per_worker`` are then unused (the cluster's own).

    Returns
    -------
    Summary
        Counts (generated, kept, errors), wall time and the per-item cost split.

    Raises
    ------
    ValueError, TypeError
        For an invalid option (named, with its valid range), no photo in ``input``, or an
        index outside the run.
    FileNotFoundError
        When ``input`` or ``depth`` is not a folder.
    RuntimeError
        When a worker process dies (killed, out of memory): the items written are complete, and
        ``resume=True`` finishes the run.

    Examples
    --------
    >>> import tempfile
    >>> out = tempfile.mkdtemp()
    >>> s = generate(out=out, scene="street", variants=2, width=48, height=32, ambient_spacing_m=8.0, progress=False)
    >>> s.generated, s.errors
    (2, 0)
    """
    if config is None:
        config = DatasetConfig(**options)
    elif options:
        raise TypeError(f"give the options as config or as keywords, not both ({', '.join(sorted(options))})")
    if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= 256:
        raise ValueError(f"workers = {workers!r} is outside the valid range [1, 256]")
    if threads_per_worker is not None and (isinstance(threads_per_worker, bool) or not isinstance(threads_per_worker, int) or not 1 <= threads_per_worker <= 1024):
        raise ValueError(f"threads_per_worker = {threads_per_worker!r} is outside the valid range [1, 1024]")
    start = time.perf_counter()
    items_dir = config.out / "items"
    items_dir.mkdir(parents=True, exist_ok=True)
    remove_temporaries(items_dir)
    remove_temporaries(config.out)
    all_sources = sources(config)
    chosen = all_sources
    if indices is not None:
        wanted = sorted(set(int(i) for i in indices))
        bad = [i for i in wanted if not 0 <= i < len(all_sources)]
        if bad:
            raise ValueError(f"indices: {bad[0]} is outside the valid range [0, {len(all_sources) - 1}] of this run's items")
        chosen = [all_sources[i] for i in wanted]
    if indices is None:  # a whole run: its manifest and config.json are written once it is complete
        for name in ("manifest.jsonl", "manifest.parquet", "config.json"):
            (config.out / name).unlink(missing_ok=True)
    summary = Summary(items=len(chosen), workers=workers)
    todo = [s for s in chosen if not (resume and verify_item(config, s.index))]
    summary.skipped = len(chosen) - len(todo)
    before = {s.index: _row_identity(config, s.index) for s in todo}
    bar = tqdm(total=len(todo), unit="item", disable=not progress, dynamic_ncols=True)
    results: Iterator[tuple[dict[str, Any], dict[str, float]]] | None = None
    try:
        results = _run_dask(config, todo, scheduler) if scheduler is not None else _run_local(config, todo, workers, threads_per_worker)
        first: float | None = None
        for row, times in results:
            now = time.perf_counter()
            first = now if first is None else first
            summary.first_to_last_s = now - first
            for k in COSTS:
                summary.cost_s[k] += times.get(k, 0.0)
            if row["status"] != "ok":
                summary.errors += 1
                summary.error_messages.append(f"item {row['index']}: {row['error']}")
                bar.set_postfix(errors=summary.errors)
            else:
                summary.generated += 1
            bar.update(1)
    except KeyboardInterrupt:
        summary.interrupted = True
    except BrokenProcessPool as e:  # a worker killed (kill -9, out of memory): what is done stays
        raise RuntimeError(
            f"a worker process died ({e}); the items written so far are complete: run again with resume=True (--resume)"
        ) from e
    finally:
        close = getattr(results, "close", None)
        if close is not None:  # the generators' own finally: the item being written is finished
            close()
        bar.close()
    if summary.interrupted:
        # The items in flight when Ctrl-C came were finished but never reached the loop
        # above: count every row this run wrote, from the disk.
        _recount(config, before, summary)
    elif indices is None:
        write_manifest(config, [s.index for s in all_sources])
        options = config.to_json()
        options.pop("out")  # the folder can move: its files do not name it
        write_json(config.out / "config.json", {"config": options, "config_sha256": config.sha256(), "skyfall_version": skyfall.__version__})
    summary.seconds = time.perf_counter() - start
    return summary


def _row_identity(config: DatasetConfig, index: int) -> tuple[int, int] | None:
    """Which file item ``index``'s row is now (inode, mtime), None without one: rows are
    replaced atomically, so a row written later is another file."""
    try:
        st = (config.out / "items" / f"{item_name(index)}.json").stat()
    except OSError:
        return None
    return (st.st_ino, st.st_mtime_ns)


def _recount(config: DatasetConfig, before: dict[int, tuple[int, int] | None], summary: Summary) -> None:
    """``summary``'s generated and errors from the rows written since ``before``."""
    summary.generated = summary.errors = 0
    summary.error_messages.clear()
    for index, was in before.items():
        now = _row_identity(config, index)
        if now is None or now == was:
            continue
        try:
            row = json.loads((config.out / "items" / f"{item_name(index)}.json").read_text())
        except (OSError, ValueError):
            continue
        if row.get("status") == "ok":
            summary.generated += 1
        else:
            summary.errors += 1
            summary.error_messages.append(f"item {index}: {row.get('error')}")


def _run_local(
    config: DatasetConfig, todo: list[ItemSource], workers: int, threads: int | None
) -> Iterator[tuple[dict[str, Any], dict[str, float]]]:
    """The items' rows and costs as they finish, in this process (each item written while the
    next renders) or in ``workers`` processes (chunks of :data:`CHUNK_ITEMS`, at most 2 in
    flight per worker, so memory stays bounded)."""
    if workers == 1 and threads is None:
        yield from render_items(Worker(config), todo)
        return
    if threads is None:
        threads = max(1, (os.cpu_count() or 1) // workers)
    pool = ProcessPoolExecutor(workers, mp_context=get_context("spawn"), initializer=_init_worker, initargs=(config, threads, os.getpid()))
    pending: set[Future[list[tuple[dict[str, Any], dict[str, float]]]]] = set()
    queue = iter(_chunks(todo, workers))
    try:
        for chunk in queue:
            pending.add(pool.submit(_work, chunk))
            if len(pending) >= 2 * workers:
                break
        while pending:
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for f in done:
                yield from f.result()
                nxt = next(queue, None)
                if nxt is not None:
                    pending.add(pool.submit(_work, nxt))
    finally:
        # Ctrl-C or an error: drop the queued items, let those in flight finish (each is
        # written atomically either way), then stop the workers.
        for f in pending:
            f.cancel()
        pool.shutdown(wait=True, cancel_futures=True)


# Per Dask worker thread: its Worker for the run's options (Dask runs tasks in threads).
_DASK_WORKERS = threading.local()


def _dask_chunk(config: DatasetConfig, chunk: list[ItemSource]) -> list[tuple[dict[str, Any], dict[str, float]]]:
    """A chunk of items on a Dask worker, with that thread's Worker for these options (made
    once), each written while the next renders, as in a local worker."""
    key = (config.sha256(), str(config.out))
    worker: Worker | None = getattr(_DASK_WORKERS, "worker", None)
    if worker is None or getattr(_DASK_WORKERS, "key", None) != key:
        worker = Worker(config)
        _DASK_WORKERS.worker, _DASK_WORKERS.key = worker, key
    return list(render_items(worker, chunk))


def _run_dask(config: DatasetConfig, todo: list[ItemSource], scheduler: Any) -> Iterator[tuple[dict[str, Any], dict[str, float]]]:
    """The items' rows and costs as they finish on a Dask cluster (chunks of
    :data:`CHUNK_ITEMS`, at most two in flight per worker thread)."""
    import dask.distributed

    dd: Any = dask.distributed  # untyped: its calls are typed Any here
    client: Any = scheduler if isinstance(scheduler, dd.Client) else dd.Client(scheduler)
    own = client is not scheduler
    pending: set[Any] = set()
    try:
        threads = max(1, sum(client.nthreads().values()))
        queue = iter(_chunks(todo, threads))
        pending = {client.submit(_dask_chunk, config, chunk, pure=False) for _, chunk in zip(range(2 * threads), queue)}
        done_iter = dd.as_completed(list(pending))
        for f in done_iter:
            pending.discard(f)
            yield from f.result()
            nxt = next(queue, None)
            if nxt is not None:
                g = client.submit(_dask_chunk, config, nxt, pure=False)
                pending.add(g)
                done_iter.add(g)
    finally:
        # Ctrl-C or an error: drop what is left (each item is written atomically either way)
        if pending:
            client.cancel(list(pending))
        if own:
            client.close()


def write_manifest(config: DatasetConfig, indices: list[int]) -> Path:
    """Gather the items' rows into ``out/manifest.jsonl`` (index order, one JSON object per line).

    Returns
    -------
    Path
        The manifest's path.
    """
    rows = []
    for i in indices:
        path = config.out / "items" / f"{item_name(i)}.json"
        try:
            rows.append(json.loads(path.read_text()))
        except (OSError, ValueError):
            rows.append({"index": i, "status": "error", "error": f"no manifest row {path.name}"})
    final = config.out / "manifest.jsonl"
    write_json(final, rows)
    if config.parquet:
        write_parquet(config.out / "manifest.parquet", rows)
    return final


def _flat(row: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """A row with nested dicts as dotted columns (``params.rain_rate_mm_h``), "inf" as inf, and
    ``files`` as a list of (name, sha256)."""
    out: dict[str, Any] = {}
    for key, value in row.items():
        if key == "files" and not prefix:
            out[key] = sorted(value.items())
        elif isinstance(value, dict):
            out.update(_flat(value, f"{prefix}{key}."))
        elif value in ("inf", "-inf"):
            out[prefix + key] = float(value)
        else:
            out[prefix + key] = value
    return out


def write_parquet(final: Path, rows: list[dict[str, Any]]) -> str:
    """The manifest's rows as a parquet table (pyarrow; ``pip install "skyfall[parquet]"``),
    atomically; its sha256. Columns: the rows' keys, nested parameters dotted, ``files`` a map
    of name to sha256; a key an item lacks (an error row's ``files``) is null."""
    import pyarrow as pa  # type: ignore[import-untyped]
    import pyarrow.parquet as pq  # type: ignore[import-untyped]

    flat = [_flat(r) for r in rows]
    names = sorted({k for r in flat for k in r})
    columns: dict[str, Any] = {}
    for name in names:
        values = [r.get(name) for r in flat]
        if name == "files":
            columns[name] = pa.array(values, type=pa.map_(pa.string(), pa.string()))
        elif name in ("camera_position_m",):
            columns[name] = pa.array(values, type=pa.list_(pa.float64()))
        elif any(isinstance(v, float) for v in values) and all(v is None or isinstance(v, (int, float)) for v in values):
            columns[name] = pa.array([None if v is None else float(v) for v in values], type=pa.float64())
        else:
            columns[name] = pa.array(values)
    table = pa.table(columns)

    def save(p: Path) -> None:
        pq.write_table(table, p, compression="zstd")

    return atomic_write(final, save)


def read_manifest(out: str | Path) -> list[dict[str, Any]]:
    """The rows of ``out/manifest.jsonl``, in index order."""
    text = (Path(out) / "manifest.jsonl").read_text()
    return [json.loads(line) for line in text.splitlines() if line.strip()]

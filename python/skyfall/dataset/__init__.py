"""Datasets: many weather variants of photos or of the bundled street, with ground truth.

``generate(out=..., input=... | scene="street", variants=N, seed=S, rain_rate_mm_h="1:50", ...)``
(and ``skyfall dataset`` on the command line) writes, per item, into ``out/items/``:

- ``NNNNNN.rain.png``: the weather image (8-bit sRGB; ``NNNNNN.rain.exr`` too with ``exr``),
- ``NNNNNN.clean.png``: the same view without weather (a photo's own pixels),
- ``NNNNNN.<layer>.npy``: each ground-truth layer asked for (``rain_alpha``, ``rain_depth_m``,
  ``transmittance``), float32 (H, W),
- ``NNNNNN.json``: its manifest row: every sampled parameter, the master seed, the skyfall
  version, the depth source (file, ground plane or scene) and the sha256 of each file; for an
  item whose input is missing, unreadable or mismatched, ``status`` "error" and the error,

or, with ``sequence=N`` (``--sequence N --fps F``), a clip per item: ``NNNNNN.rain.mp4`` and
``NNNNNN.clean.mp4`` (:func:`skyfall.video.write_video`; ``video_lossless`` keeps every byte)
of N frames rendered at ``time_s = k / fps`` (world-anchored rain falling over the static photo
or street), each layer as one float32 (N, H, W) ``.npy`` stack, and the row's ``sequence`` and
``fps``. Frames are streamed to the encoder one at a time (the layer stacks aside, an item holds
one frame, however long the clip),

and, once every item is done, ``out/manifest.jsonl`` (the rows in index order; also
``out/manifest.parquet`` with ``parquet=True``, through pyarrow) and
``out/config.json`` (the options). Item ``i``'s parameters come from
``SeedSequence([seed, i])`` alone (:mod:`skyfall.dataset.sample`), so any item can be
regenerated alone (``indices=[i]``) and the bytes do not depend on ``workers``. Files are
written atomically (:mod:`skyfall.dataset.io`); ``resume=True`` regenerates only the items
whose files are missing or fail their checksum, so a run killed with ``kill -9`` and resumed
writes the same bytes as one never interrupted.

Modules
-------
sample
    :class:`DatasetConfig` (a run's options) and :func:`sample_item` (one item's parameters).
io
    Reading photos and depth maps, and atomic writes of the item's files.
item
    One item: the :class:`~skyfall.dataset.item.Worker` that renders it and writes its files.
run
    :func:`generate`: the items to make, run here, in worker processes or on a Dask cluster;
    the manifest.
"""

from skyfall.dataset.run import Summary, generate, read_manifest, sources, write_manifest
from skyfall.dataset.sample import DatasetConfig, sample_item

__all__ = ["DatasetConfig", "Summary", "generate", "read_manifest", "sample_item", "sources", "write_manifest"]

"""What skyfall.augment (image in, image out) costs over the renderer it wraps, at 1080p, in one
run with the rows timed in alternating blocks (timing.block_times_s), and albumentations'
RandomRain on the same photo. Writes benches/results/augment.md and augment.json.

Rows: render_srgb8 of a PhotoScene built once (the floor: a user rendering the same photo
again), the same with the PhotoScene built per call (what a pipeline of new photos does by
hand), augment, and the albumentations adapter inside A.Compose. Then a stream of images of
three sizes through augment, to show its renderers are reused (one per size, made once).
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np
from skimage import data, transform
from timing import block_times_s

from skyfall import PhotoScene, Renderer, Weather, augment
import skyfall.augmentation as augment_module

RESULTS = Path(__file__).parent / "results"
W, H = 1920, 1080


def photo(width: int, height: int) -> np.ndarray:
    return np.round(transform.resize(data.rocket(), (height, width), anti_aliasing=True) * 255).astype(np.uint8)


def main() -> None:
    import albumentations as A

    from skyfall.adapters import AlbumentationsWeather

    img = photo(W, H)
    weather = Weather(rain_rate_mm_h=25.0)
    r = Renderer(W, H, backend="cpu")
    scene = PhotoScene(img)
    pipe = A.Compose([AlbumentationsWeather(rain_rate_mm_h=25.0, layers=())], seed=1)
    rain = A.Compose([A.RandomRain(p=1.0)], seed=1)
    fns = {
        "render_srgb8, PhotoScene built once": lambda: r.render_srgb8(scene, weather, seed=1),
        "PhotoScene(image) + render_srgb8 per call": lambda: r.render_srgb8(PhotoScene(img), weather, seed=1),
        "skyfall.augment(image, rain_rate_mm_h=25)": lambda: augment(img, rain_rate_mm_h=25.0, seed=1),
        "A.Compose([AlbumentationsWeather(...)])": lambda: pipe(image=img),
        "A.Compose([A.RandomRain()]) (flat rain, for scale)": lambda: rain(image=img),
    }
    blocks = block_times_s(fns, blocks=5, per_block=3)
    med = {k: statistics.median(v) for k, v in blocks.items()}
    by_hand = blocks["PhotoScene(image) + render_srgb8 per call"]
    once = blocks["render_srgb8, PhotoScene built once"]
    aug = blocks["skyfall.augment(image, rain_rate_mm_h=25)"]
    over_hand = [a / b for a, b in zip(aug, by_hand)]
    over_once = [a / b for a, b in zip(aug, once)]

    # a stream of three sizes: renderers made once per size
    augment_module._RENDERERS.clear()
    sizes = [(640, 360), (1280, 720), (800, 600)]
    stream = [photo(w, h) for w, h in sizes] * 4
    made = []
    real = augment_module.Renderer

    def counting(*a: object, **k: object) -> Renderer:
        made.append(a[:2])
        return real(*a, **k)  # type: ignore[arg-type]

    augment_module.Renderer = counting  # type: ignore[misc]
    try:
        t0 = time.perf_counter()
        for k, im in enumerate(stream):
            augment(im, rain_rate_mm_h=25.0, seed=k)
        stream_s = time.perf_counter() - t0
    finally:
        augment_module.Renderer = real  # type: ignore[misc]

    env = {"cpus": os.cpu_count(), "machine": platform.machine(), "python": platform.python_version(), "date": time.strftime("%Y-%m-%d"), "load": os.getloadavg()[0]}
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "augment.json").write_text(
        json.dumps({"env": env, "frame": [W, H], "blocks_s": blocks, "augment_over_by_hand": over_hand, "augment_over_once": over_once, "stream": {"images": len(stream), "renderers_made": len(made), "s": stream_s}}, indent=2) + "\n"
    )
    lines = [
        "# skyfall.augment: its overhead",
        "",
        f"{W} x {H} (scikit-image's rocket, resized), 25 mm/h, CPU backend, {env['cpus']} CPUs, load {env['load']:.1f}, {env['date']}. "
        "Medians of 5 alternating blocks of 3 calls each (benches/augment.py).",
        "",
        "| call | median | per block |",
        "|---|---|---|",
    ]
    for k, v in blocks.items():
        lines.append(f"| {k} | {1e3 * med[k]:.1f} ms | {', '.join(f'{1e3 * x:.0f}' for x in v)} ms |")
    lines += [
        "",
        f"- augment over the same work by hand (PhotoScene + render_srgb8 per call): {statistics.median(over_hand):.3f}x "
        f"(blocks {min(over_hand):.3f}-{max(over_hand):.3f}); the goal is at most 1.05x.",
        f"- augment over render_srgb8 of a scene built once: {statistics.median(over_once):.2f}x: the photo scene model "
        "(the sky mask, the depth it assumes, the airlight) is built per image; render the same photo again through a "
        "PhotoScene you keep to skip it.",
        f"- A stream of {len(stream)} images in three sizes ({', '.join(f'{w}x{h}' for w, h in sizes)}) made "
        f"{len(made)} renderers (one per size) in {stream_s:.2f} s.",
    ]
    (RESULTS / "augment.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

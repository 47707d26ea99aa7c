"""Sliders over a scene in Jupyter: :func:`explore` (ipywidgets, the ``jupyter`` extra).

Each slider's move re-renders a small frame (:meth:`skyfall.Renderer.render_srgb8`) and shows
it as PNG in an ``ipywidgets.Image``. In a notebook run without a live kernel (nbmake, a
static page) the widget is built and shown once, not interactive.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from typing import Any

import ipywidgets  # type: ignore[import-untyped]  # ipywidgets 8 ships no types
import numpy as np
from numpy.typing import NDArray

from skyfall import display
from skyfall._validate import integer
from skyfall.render import Renderer
from skyfall.scenes import BoxScene, PhotoScene
from skyfall.weather import Weather

__all__ = ["SLIDER_SPANS", "Explorer", "explore"]

SLIDER_SPANS: dict[str, tuple[float, float]] = {
    "rain_rate_mm_h": (0.0, 100.0),
    "wind_x_m_s": (-20.0, 20.0),
    "visibility_m": (10.0, 100_000.0),
    "exposure_s": (1.0 / 4000.0, 0.1),
    "time_s": (0.0, 2.0),
}
"""What each slider spans (within the parameter's valid range, ``skyfall._core.RANGES``):
rain rate, mm/h; the wind's x component (across a default camera's view), m/s; visibility,
m (log slider; at its top, clear air: ``inf``); the camera's shutter time, s (log slider); the
frame's time, s."""


class Explorer:
    """The widget :func:`explore` returns: shows itself in Jupyter (``widget``, an
    ``ipywidgets.VBox``), with its parts for code.

    Attributes
    ----------
    widget : ipywidgets.VBox
        The sliders above the picture.
    sliders : dict of str to ipywidgets slider
        By parameter: ``rain_rate_mm_h``, ``wind_x_m_s``, ``visibility_m``, ``time_s``, and
        ``exposure_s`` for a box scene (a photo keeps the exposure it was taken with).
        Setting a slider's ``value`` re-renders, as moving it does.
    image : ipywidgets.Image
        The frame as PNG bytes (``image.value``).
    renderer : skyfall.Renderer
        The renderer the frames come from.
    """

    def __init__(self, scene: BoxScene | PhotoScene, renderer: Renderer, weather: Weather, seed: int, sliders: dict[str, Any]) -> None:
        self.scene = scene
        self.renderer = renderer
        self.weather = weather
        self.seed = seed
        self.sliders = sliders
        self.image = ipywidgets.Image(format="png", width=renderer.width, height=renderer.height)
        self.widget = ipywidgets.VBox([*sliders.values(), self.image])
        for s in sliders.values():
            s.observe(self._changed, names="value")
        self.update()

    def parameters(self) -> dict[str, Any]:
        """The frame the sliders stand at, as :meth:`skyfall.Renderer.render_srgb8`'s
        arguments: ``weather``, ``time_s``, ``seed`` and, for a box scene, ``camera``."""
        v = {name: float(s.value) for name, s in self.sliders.items()}
        wind = (v["wind_x_m_s"], *self.weather.wind_m_s[1:])
        clear = v["visibility_m"] >= SLIDER_SPANS["visibility_m"][1]  # the slider's top: clear air
        visibility = math.inf if clear else v["visibility_m"]
        weather = dataclasses.replace(self.weather, rain_rate_mm_h=v["rain_rate_mm_h"], wind_m_s=wind, visibility_m=visibility)
        args: dict[str, Any] = {"weather": weather, "time_s": v["time_s"], "seed": self.seed}
        if isinstance(self.scene, BoxScene):
            camera = copy.copy(self.scene.camera)
            camera.exposure_s = v["exposure_s"]
            args["camera"] = camera
        return args

    def render(self) -> NDArray[np.uint8]:
        """The frame the sliders stand at, uint8 sRGB (H, W, 3)."""
        image: NDArray[np.uint8] = self.renderer.render_srgb8(self.scene, **self.parameters())  # no layers: the image
        return image

    def update(self) -> None:
        """Render the frame the sliders stand at into ``image``."""
        self.image.value = display.png_bytes(self.render())

    def _changed(self, change: Any) -> None:
        self.update()

    def _repr_mimebundle_(self, **kwargs: Any) -> Any:
        """Jupyter shows the widget (ipywidgets' own bundle: the live view, and its text)."""
        return self.widget._repr_mimebundle_(**kwargs)


def explore(
    scene: BoxScene | PhotoScene,
    *,
    width: int = 320,
    height: int = 180,
    weather: Weather | None = None,
    seed: int = 0,
    backend: str = "cpu",
) -> Explorer:
    """Sliders for rain rate, wind, visibility, exposure and time over a scene, re-rendering a
    small frame as they move (a 320 x 180 street frame in about 30 ms on 2 cores; a move of the
    rain rate or the visibility, which change the sky, adds its ambient-light map lit from the
    scene's horizon: about 5 ms under an overcast sky, 14 ms under a sky with a sun, after a
    first move that finds the horizon, about 0.4 s).

    Parameters
    ----------
    scene : BoxScene or PhotoScene
        What to show. A photo is rendered at its own size (``width`` and ``height`` are for
        box scenes).
    width, height : int
        Frame size of a box scene, px, each in [1, 16384] (small: each move renders a frame).
    weather : Weather, optional
        Where the sliders start, and every field they do not set (default: 10 mm/h). Values
        outside a slider's span (:data:`SLIDER_SPANS`) start at its end (infinite visibility at
        the visibility slider's top, which stands for clear air).
    seed : int
        Seed of the rain, in [0, 2^64).
    backend : {"cpu", "gpu", "auto"}
        The renderer's backend.

    Returns
    -------
    Explorer
        Shown by Jupyter as the sliders and the picture.

    Raises
    ------
    TypeError
        When ``scene`` is not a BoxScene or PhotoScene or ``weather`` not a Weather.
    """
    if not isinstance(scene, (BoxScene, PhotoScene)):
        raise TypeError(f"scene must be a BoxScene or PhotoScene, got {type(scene).__name__}")
    weather = weather if weather is not None else Weather(rain_rate_mm_h=10.0)
    if not isinstance(weather, Weather):
        raise TypeError(f"weather must be a skyfall.Weather, got {type(weather).__name__}")
    integer("seed", seed, 0, 2**64 - 1)
    if isinstance(scene, PhotoScene):
        h, w = scene.shape
        renderer = Renderer(w, h, backend=backend)
    else:
        renderer = Renderer(width, height, backend=backend)

    def start(name: str, value: float) -> float:
        lo, hi = SLIDER_SPANS[name]
        return min(max(value, lo), hi)

    # Every slider renders as it moves (about 30 ms a 320 x 180 frame of the street on 2 cores).
    # The rain rate and the visibility change the sky: its ambient-light map is lit from the
    # scene's horizon, found at the first such move (about 0.4 s, once), then about 5 ms a move
    # under an overcast sky and 14 ms under a sky with a sun (benches/results/sweeps.md).
    def linear(name: str, description: str, value: float, step: float) -> Any:
        lo, hi = SLIDER_SPANS[name]
        return ipywidgets.FloatSlider(
            value=start(name, value), min=lo, max=hi, step=step, description=description, readout_format=".3g", continuous_update=True
        )

    def log(name: str, description: str, value: float) -> Any:
        lo, hi = SLIDER_SPANS[name]
        return ipywidgets.FloatLogSlider(
            value=start(name, value),
            base=10.0,
            min=math.log10(lo),
            max=math.log10(hi),
            step=0.05,
            description=description,
            readout_format=".3g",
            continuous_update=True,
        )

    sliders: dict[str, Any] = {
        "rain_rate_mm_h": linear("rain_rate_mm_h", "rain mm/h", weather.rain_rate_mm_h, 0.5),
        "wind_x_m_s": linear("wind_x_m_s", "wind x m/s", weather.wind_m_s[0], 0.5),
        "visibility_m": log("visibility_m", "visibility m", weather.visibility_m),
    }
    if isinstance(scene, BoxScene):
        sliders["exposure_s"] = log("exposure_s", "exposure s", scene.camera.exposure_s)
    sliders["time_s"] = linear("time_s", "time s", 0.0, 1.0 / 30.0)
    return Explorer(scene, renderer, weather, seed, sliders)

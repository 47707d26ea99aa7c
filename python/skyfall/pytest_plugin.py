"""skyfall's pytest plugin, loaded by pytest through the ``pytest11`` entry point
(``skyfall = "skyfall.pytest_plugin"``) wherever skyfall is installed.

It adds one fixture, ``skyfall_renderer``: the session's :class:`skyfall.testing.RendererCache`
(``skyfall_renderer(width, height)`` is a :class:`skyfall.Renderer` of that size on the CPU
backend, made once per size and session). With :func:`skyfall.testing.with_weather`, a rain
sweep over your model is a parametrised test::

    import pytest
    from skyfall.testing import with_weather

    @pytest.mark.parametrize("rate", [0.0, 5.0, 25.0])
    def test_detector_survives_rain(rate, skyfall_renderer):
        image = load_my_image()                                   # uint8 (H, W, 3)
        h, w = image.shape[:2]
        rainy = with_weather(image, rain_rate_mm_h=rate, renderer=skyfall_renderer(w, h))
        assert my_model(rainy) == my_model(image)

Importing this module imports nothing of skyfall: the fixture does, when a test asks for it,
so the plugin costs a pytest run that does not use it nothing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from skyfall.testing import RendererCache

__all__ = ["skyfall_renderer"]


@pytest.fixture(scope="session")
def skyfall_renderer() -> RendererCache:
    """Renderers by size for the session: ``skyfall_renderer(width, height)`` (CPU backend)."""
    from skyfall.testing import RENDERERS

    return RENDERERS

"""skyfall: physically grounded weather for images.

Submodules
----------
physics
    Air properties, raindrop terminal velocity, the Marshall-Palmer drop-size
    distribution and rain extinction, vectorised over numpy arrays.
rain
    Precomputed rain-streak textures (Yoshida, Dobashi & Yamamoto).
io
    Image files through OpenImageIO (EXR float, PNG sRGB 8-bit).
"""

from skyfall import io, physics, rain
from skyfall._core import SkyfallError, __version__

__all__ = ["SkyfallError", "__version__", "io", "physics", "rain"]

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
scenes
    Photo scenes with depth and procedural box scenes (``scenes.street()``).
clouds
    Particle clouds, Harris' illumination and the attenuation volume (Shimada, Shinya,
    Shiraishi & Harada).
sky
    CIE skies, sky illuminance with occlusion and the ambient-light map (Yamamoto & Tadamura).
snow
    The snow cover (Koitabashi, Matsubara, Moriya & Takahashi): ``Weather(snow_cover=...)``.
dataset
    Datasets of weather variants with ground truth (imported on use: ``from skyfall import dataset``).

Rendering: ``Renderer(width, height).render(scene, Weather(...))`` gives a :class:`Frame`;
``augment(image, rain_rate_mm_h=25.0)`` puts weather on any image and gives it back.
"""

from skyfall import clouds, io, physics, rain, scenes, sky, snow
from skyfall.augmentation import augment
from skyfall._core import GpuUnavailableError, SkyfallError, __version__
from skyfall.camera import Camera
from skyfall.lights import PointLight, SpotLight
from skyfall.render import Frame, Renderer
from skyfall.scenes import PhotoScene
from skyfall.weather import Weather

__all__ = [
    "Camera",
    "Frame",
    "GpuUnavailableError",
    "PhotoScene",
    "PointLight",
    "Renderer",
    "SkyfallError",
    "SpotLight",
    "Weather",
    "__version__",
    "augment",
    "clouds",
    "io",
    "physics",
    "rain",
    "scenes",
    "sky",
    "snow",
]

"""satchain: Earth-observation satellite image-chain simulation and image-quality measurement.

The chain follows one line (see ARCHITECTURE): scene -> optics -> detector + motion -> sampled image,
with the same transfer functions used for prediction (``satchain.tf``) and simulation, and
independent measurement (``satchain.measure``) to check them.
"""

from satchain.errors import (
    ConfigError,
    InputError,
    ResourceLimitError,
    SatchainError,
    SatchainIOError,
)
from satchain.system import ImagingSystem, load_preset, load_system

__version__ = "0.1.0"

__all__ = [
    "ConfigError",
    "ImagingSystem",
    "InputError",
    "ResourceLimitError",
    "SatchainError",
    "SatchainIOError",
    "__version__",
    "load_preset",
    "load_system",
]

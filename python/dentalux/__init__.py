"""dentalux: spectral Monte Carlo rendering of teeth and dental restorative materials.

Units everywhere: lengths in mm, coefficients in 1/mm, wavelengths in nm.
"""

from dentalux import _core
from dentalux.slab import Layer, SlabResult

__version__ = _core.__version__

__all__ = ["Layer", "SlabResult", "__version__"]

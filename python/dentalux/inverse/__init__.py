"""Inversion: measured total transmittance and reflectance -> absorption and scattering.

``fit(tt=..., tr=..., n=..., g=..., thickness=..., model="mc")`` -> :class:`FitResult`;
``fit_table(path_or_columns, ...)`` fits a spectral batch and can write a material spectrum
TOML file. Forward models (``mc``, ``ad``, ``telegrapher``, ``km``) live in
:mod:`dentalux.inverse.models`. Units: mm, 1/mm, nm.
"""

from dentalux.inverse.fit import fit
from dentalux.inverse.models import MODELS
from dentalux.inverse.result import FitResult
from dentalux.inverse.table import fit_table, write_spectrum_toml

__all__ = ["MODELS", "FitResult", "fit", "fit_table", "write_spectrum_toml"]

"""The reading engine: what an instrument reads off a layered specimen, band by band, with
standard errors that keep every correlation (:mod:`dentalux.reading.engine`)."""

from dentalux.reading.engine import DEFAULT_SOLVER, measure, stacks
from dentalux.reading.spectra import CHANNELS, ReadSpectra

__all__ = ["CHANNELS", "DEFAULT_SOLVER", "ReadSpectra", "measure", "stacks"]

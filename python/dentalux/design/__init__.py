"""Restoration design: which thickness of each candidate material matches a target tooth.

- :func:`optimise` searches 1 to 3 layers (thickness ranges, a total range) on a substrate
  for a target colour (and TP) as an instrument reads it (:mod:`dentalux.design.search`);
- :func:`specimen` and :func:`backings` build the layered specimen that the Monte Carlo
  reads for given thicknesses (:mod:`dentalux.design.substrates`), :func:`read` reads it;
- :mod:`dentalux.design.forward` is the fast model, :mod:`dentalux.design.verify` the Monte
  Carlo check, :mod:`dentalux.design.plot` the ΔE00 plane of a two-layer design.

docs/design.md describes the method, its measured accuracy and its limits.
"""

from __future__ import annotations

from dentalux.design.constraints import parse_fixed_layers
from dentalux.design.search import DesignResult, optimise
from dentalux.design.substrates import backings, specimen
from dentalux.design.targets import Target


def read(layers, substrate: str = "dentin", cement=None, **kwargs):
    """The Monte Carlo read (:func:`dentalux.dental.read`) of ``layers`` [(material, mm)] on
    ``substrate`` (with an optional ``cement`` (material, mm)): the forward model that a
    design is verified with. ``kwargs`` go to dental.read (instrument, bands, photons, ...);
    an opaque core's reflectance replaces the instrument's backings."""
    from dentalux import dental

    return dental.read(specimen(layers, substrate, cement), **backings(substrate), **kwargs)


__all__ = ["DesignResult", "Target", "backings", "optimise", "parse_fixed_layers", "read",
           "specimen"]

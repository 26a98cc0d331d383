"""A deterministic reading of a layered specimen: the radiative transfer equation of a plane
stack solved per spatial frequency by discrete ordinates (quadrature.py, operators.py,
stack.py) and read through the instrument's lit region and window (window.py).

Where it holds: a beam along the normal, a detector cone (or the hemisphere) about the
normal, and lit regions and windows that are concentric discs or rings. The specimen is
laterally infinite; a finite specimen's rim is corrected by a Monte Carlo walk that tallies
only what the rim takes (the reading engine). It has no noise; its discretisation error is
checked against the slab Monte Carlo (tests/test_layered.py).
"""

from dentalux.reading.layered.operators import reuse, share
from dentalux.reading.layered.stack import local_parts, responses, responses_many
from dentalux.reading.layered.window import order_sums

__all__ = ["local_parts", "order_sums", "responses", "responses_many", "reuse", "share"]

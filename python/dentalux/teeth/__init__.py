"""Procedural teeth: a maxillary central incisor and a maxillary first molar, each as two
nested closed triangle meshes (enamel outer surface, dentin surface) built from signed
distance fields with marching cubes. Frame, units and boundaries: :mod:`dentalux.teeth.tooth`;
design and sources: ``docs/teeth.md``."""

from dentalux.teeth.incisor import incisor
from dentalux.teeth.mesh import read_obj, write_obj
from dentalux.teeth.molar import molar
from dentalux.teeth.tooth import FRAME, MeshError, Tooth

__all__ = ["FRAME", "MeshError", "Tooth", "incisor", "molar", "read_obj", "write_obj"]

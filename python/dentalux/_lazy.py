"""Modules imported on first use. colour-science takes about 1 s to import, half of it its
``colour.plotting`` (matplotlib's pyplot, fonts, colour-space diagrams), which its
``__init__`` imports although dentalux never calls it: every command line call paid that at
start-up, `--help` included. Here ``colour`` is imported when an attribute is first read,
and its ``plotting`` subpackage only when one of its own attributes is."""

from __future__ import annotations

import importlib
import sys
from types import ModuleType


class LazyModule(ModuleType):
    """Stands for the module ``name`` and imports it when an attribute is first read, after
    calling ``before()`` (if given)."""

    def __init__(self, name: str, before=None):
        super().__init__(name)
        self._module: ModuleType | None = None
        self._before = before

    def __getattr__(self, attr: str):
        if self._module is None:
            if sys.modules.get(self.__name__) is self:
                del sys.modules[self.__name__]  # the real module takes its place there
            if self._before is not None:
                self._before()
            self._module = importlib.import_module(self.__name__)
        return getattr(self._module, attr)


def _defer_plotting() -> None:
    # a stand-in registered first is what colour's own `from colour import plotting` finds
    # (Python looks in sys.modules before importing a submodule); the import system reads
    # only attributes a module defines (__spec__), which trigger nothing
    if "colour" not in sys.modules:
        sys.modules.setdefault("colour.plotting", LazyModule("colour.plotting"))


colour = LazyModule("colour", before=_defer_plotting)

"""A module imported on first use: colour-science takes about 1.2 s to import (it pulls in
its plotting and matplotlib), which every command line call paid at start-up, `--help`
included, though only colour and spectral commands use it."""

from __future__ import annotations

import importlib
from types import ModuleType


class LazyModule(ModuleType):
    """Stands for the module ``name`` and imports it when an attribute is first read."""

    def __init__(self, name: str):
        super().__init__(name)
        self._module: ModuleType | None = None

    def __getattr__(self, attr: str):
        if self._module is None:
            self._module = importlib.import_module(self.__name__)
        return getattr(self._module, attr)


colour = LazyModule("colour")

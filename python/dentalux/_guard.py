"""Every native call reports errors as ordinary Python exceptions.

PyO3 raises ``PanicException`` (a ``BaseException``, which ``except Exception`` does not
catch) for a panic outside the binding's worker threads, and ``OverflowError`` for an integer
argument that does not fit the native type (``threads=-1``, ``n_photons=2**70``).
:func:`install` wraps the functions of ``dentalux._core`` so that a panic becomes
``RuntimeError`` and an overflow ``ValueError`` naming the function; the Python wrappers
(``dentalux.render``, ``dentalux.slab``) check their arguments first and name them.
"""

from __future__ import annotations

import functools

NATIVE = ("slab_simulate", "render_band", "render_bands", "camera_project", "shape_contains",
          "phase_sample_cos", "phase_eval", "panic_in_worker")


def guarded(fn, name: str):
    """``fn`` with PanicException -> RuntimeError and OverflowError -> ValueError."""

    @functools.wraps(fn)
    def call(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except OverflowError as exc:
            raise ValueError(f"{name}: an integer argument is out of range for the core "
                             f"({exc})") from None
        except BaseException as exc:
            if type(exc).__name__ == "PanicException":
                raise RuntimeError(f"internal error in dentalux core ({name}): {exc}") from None
            raise

    call.__dentalux_guarded__ = True
    return call


def install(core) -> None:
    """Wrap the native functions of ``core`` in place (idempotent)."""
    for name in NATIVE:
        fn = getattr(core, name, None)
        if fn is not None and not getattr(fn, "__dentalux_guarded__", False):
            setattr(core, name, guarded(fn, name))

"""Image files: linear EXR (RGB and spectral), 8-bit PNG, numpy arrays.

- ``image.exr``: linear sRGB, float32 channels R, G, B (no transfer function applied).
- ``spectral.exr``: one float32 channel per band, named as in the spectral OpenEXR layout of
  Fichet, Pacanowski and Wilkie (JCGT 2021): ``S0.<wavelength>nm`` with a comma as the
  decimal separator, e.g. ``S0.450,000000nm`` (S0 = emissive / radiance). The band
  wavelengths are also stored in the header attribute ``wavelengths_nm``.
- PNG via Pillow (8-bit sRGB-encoded RGB).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import OpenEXR
from PIL import Image

_SPECTRAL = re.compile(r"^S0\.(\d+),(\d+)nm$")


def spectral_channel_name(wavelength_nm: float) -> str:
    """``450.0`` -> ``'S0.450,000000nm'``."""
    return "S0." + f"{float(wavelength_nm):.6f}".replace(".", ",") + "nm"


def _header() -> dict:
    return {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}


def write_exr_rgb(path, rgb: np.ndarray) -> None:
    """Write an H x W x 3 linear RGB float image."""
    rgb = np.ascontiguousarray(rgb, dtype=np.float32)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise ValueError(f"rgb shape {rgb.shape}: expected (height, width, 3)")
    channels = {c: np.ascontiguousarray(rgb[:, :, i]) for i, c in enumerate("RGB")}
    with OpenEXR.File(_header(), channels) as f:
        f.write(str(path))


def write_exr_spectral(path, cube: np.ndarray, wavelengths_nm) -> None:
    """Write an H x W x bands float image, one channel per band (see module doc)."""
    cube = np.asarray(cube, dtype=np.float32)
    wl = np.asarray(wavelengths_nm, dtype=float).ravel()
    if cube.ndim != 3 or cube.shape[2] != len(wl):
        raise ValueError(f"cube shape {cube.shape}: expected (height, width, {len(wl)})")
    channels = {spectral_channel_name(w): np.ascontiguousarray(cube[:, :, i])
                for i, w in enumerate(wl)}
    header = _header()
    header["wavelengths_nm"] = ",".join(f"{w:.6f}" for w in wl)
    with OpenEXR.File(header, channels) as f:
        f.write(str(path))


def _channels(path) -> dict[str, np.ndarray]:
    if not Path(path).is_file():
        raise FileNotFoundError(f"no such EXR file: {path}")
    out = {}
    with OpenEXR.File(str(path), separate_channels=True) as f:
        for name, ch in f.channels().items():
            out[name] = np.array(ch.pixels)
    return out


def read_exr_rgb(path) -> np.ndarray:
    """Read an RGB EXR written by :func:`write_exr_rgb` -> H x W x 3 float32."""
    ch = _channels(path)
    return np.stack([ch["R"], ch["G"], ch["B"]], axis=-1)


def read_exr_spectral(path) -> tuple[np.ndarray, np.ndarray]:
    """Read a spectral EXR -> (H x W x bands float32, wavelengths [nm]), sorted by wavelength."""
    ch = _channels(path)
    bands = []
    for name, arr in ch.items():
        m = _SPECTRAL.match(name)
        if m:
            bands.append((float(f"{m.group(1)}.{m.group(2)}"), arr))
    if not bands:
        raise ValueError(f"{path}: no spectral channels named S0.<wavelength>nm")
    bands.sort(key=lambda b: b[0])
    return np.stack([b[1] for b in bands], axis=-1), np.array([b[0] for b in bands])


def write_png(path, srgb8: np.ndarray) -> None:
    """Write an H x W x 3 uint8 (already sRGB-encoded) image."""
    arr = np.asarray(srgb8)
    if arr.dtype != np.uint8 or arr.ndim != 3 or arr.shape[2] not in (3, 4):
        raise ValueError(f"png: expected uint8 (height, width, 3), got {arr.dtype} {arr.shape}")
    Image.fromarray(arr).save(str(path))


def save_npy(path, array: np.ndarray) -> None:
    """Save a numpy array (e.g. the raw H x W x bands radiance)."""
    np.save(str(path), np.asarray(array))


def load_npy(path) -> np.ndarray:
    """Load a numpy array saved by :func:`save_npy`."""
    if not Path(path).is_file():
        raise FileNotFoundError(f"no such file: {path}")
    return np.load(str(path))

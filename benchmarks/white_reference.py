"""The natural incisor read through contact-probe-3mm and a ring probe, calibrated on white
tiles (docs/instruments.md, "A white reference tile"; docs/notes/2026-12-07-white-reference.md).

Every tile and the ring probe are assumed (the note says why). Run:
    PYTHONPATH=python python benchmarks/white_reference.py [auto|monte-carlo]
"""

import sys
from types import SimpleNamespace

from dentalux import dental, instrument, instrument_classes
from dentalux.white_reference import WhiteReference

BANDS = [450.0, 500.0, 550.0, 600.0, 650.0]


class PowerLawTile:
    """g 0, constant n and mua; mus' = mus550 (lambda / 550 nm)^-b."""

    def __init__(self, mus550, b=0.0, n=1.35, mua=1e-4):
        self.mus550, self.b, self.n, self.mua = mus550, b, n, mua
        self.name = f"tile mus' {mus550:g}/mm at 550 nm, b {b:g}, n {n:g}"

    def at(self, lam):
        return SimpleNamespace(mua=self.mua, mus=self.mus550 * (lam / 550.0) ** -self.b,
                               g=0.0, n=self.n, fd=0.0)


def tile(mus550, b=0.0, n=1.35, cert=0.99):
    t = PowerLawTile(mus550, b, n)
    return WhiteReference(thickness_mm=10.0, reflectance=cert, material=t.name, resolved=t)


TILES = [("none", None)] + [(f"mus' {m}/mm", tile(m)) for m in (2, 5, 20, 100)] \
    + [(f"mus' 5/mm at 550, b {b}", tile(5, b)) for b in (1, 2, 4)] \
    + [("ceramic-like mus' 20/mm, n 1.5, 0.90", tile(20, 0.0, 1.5, 0.90))]
RING = instrument.Instrument(
    name="ring-probe", geometry="0-d", illuminated_diameter_mm=3.0,
    illuminated_inner_diameter_mm=2.0, viewed_diameter_mm=1.2, backing_black=0.04,
    backing_white=0.85, specimen_diameter_mm=10.0, instrument_class="clinical-contact-probe")


def main(solver="auto"):
    specimen = instrument_classes.natural_incisor()
    for inst in (instrument.get("contact-probe-3mm"), RING):
        for label, t in TILES:
            q = inst if t is None else inst.override(white_reference=t)
            m = dental.read(specimen, instrument=q, bands=BANDS, photons=20_000, seed=1,
                            solver=solver)
            lab, err = m.lab_white, m.error("lab_white")
            print(f"{inst.name:18s} {label:38s} " + " ".join(
                f"{v:7.2f} ± {e:4.2f}" for v, e in zip(lab, err, strict=True)))


if __name__ == "__main__":
    main(*sys.argv[1:])

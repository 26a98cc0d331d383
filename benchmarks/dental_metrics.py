"""Benchmark: full-spectrum (41 bands, 380-780 nm) dental metrics of one disc. Goal < 10 s.

Prints seconds, photons per second and the Monte Carlo standard errors of TP, TP00, CR and OP
for each estimator, so time and precision are read together. Usage:

    .venv/bin/python benchmarks/dental_metrics.py [MATERIAL] [THICKNESS_MM] [PHOTONS]
"""

from __future__ import annotations

import sys

from dentalux import dental


def main() -> None:
    material = sys.argv[1] if len(sys.argv) > 1 else "dentin"
    thickness = float(sys.argv[2]) if len(sys.argv) > 2 else 1.0
    photons = int(sys.argv[3]) if len(sys.argv) > 3 else dental.DEFAULT_PHOTONS
    print(f"{material}, {thickness} mm, 41 bands, {photons} photons per band and run")
    for estimator in ("weighted", "analog"):
        m = dental.metrics(material, thickness, photons=photons, estimator=estimator,
                           instrument="infinite")
        e = m.stderr
        print(
            f"{estimator:9s} {m.seconds:6.2f} s  {m.photons / m.seconds:12,.0f} photons/s  "
            f"TP {m.tp:6.2f} ± {e['tp']:.3f}  TP00 {m.tp00:6.2f} ± {e['tp00']:.3f}  "
            f"CR {m.cr:.4f} ± {e['cr']:.4f}  OP {m.op:5.2f} ± {e['op']:.3f}  "
            f"goal < 10 s: {'met' if m.seconds < 10 else 'MISSED'}"
        )


if __name__ == "__main__":
    main()

"""A measured leaf spectrum as ``vm.read_measured`` reads it: the CSV file the fitting tests hand to ``virtspec fit``."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

__all__ = ["write_measured"]


def write_measured(path: Path, wavelengths: Sequence[float], reflectance: Sequence[float],
                   transmittance: Sequence[float], uncertainty: float = 0.02) -> Path:
    """``path`` holding R and T at ``wavelengths``, each with the half-width ``uncertainty``."""

    rows = ["wavelength,reflectance,reflectance_uncertainty,transmittance,transmittance_uncertainty"]
    rows += [f"{a},{r},{uncertainty},{t},{uncertainty}" for a, r, t in zip(wavelengths, reflectance, transmittance)]
    path.write_text("\n".join(rows) + "\n")
    return path

"""
Certified Klems BSDF files (WINDOW 6 XML) from the goniophotometer
===================================================================

Building-simulation and lighting tools (LBNL WINDOW, Radiance's ``BSDF`` material,
EnergyPlus) exchange a fenestration layer's scattering as Klems matrices: for each of
the 145 patches of incidence (:mod:`virtspec_mi.exchange.klems_basis`) and each of the
145 outgoing patches, the BSDF averaged over the outgoing patch, for light incident on
the front and on the back, reflected and transmitted — four matrices in one XML file.

:func:`virtspec_mi.applications.klems.measure.klems_measure` measures them with the
goniophotometer (:func:`virtspec_mi.gonio`); this module holds the matrices
(:class:`KlemsMeasurement`), their files and their independent check:

- **incidence** at every patch centre (θ the ring's middle, 0 for the cap), by a
  collimated beam whose source lies at azimuth φ_patch + 180° (the Klems convention:
  an incident patch (θ, φ) is light *travelling* towards azimuth φ, so that a mirror and a
  clear pane both give diagonal matrices — Radiance's ``fi_getvec``/``bi_getvec``);
- **outgoing** counts binned on the ring bounds (θo, both hemispheres) × a uniform φo
  grid on which every patch boundary is a bin edge (480 bins of 0.75° for the full
  basis), so the exact integer counts add up to the patches' counts with nothing
  interpolated (:meth:`KlemsBasis.aggregation`);
- **back side**: the specimen turned over (:mod:`virtspec_mi.plugins.bsdfs.flipped`, or a scene
  of its own, e.g. a leaf's ``side="abaxial"``).

Patch value (the file's number): f_io = (m_io/N_i)/Λ_o (sr⁻¹), Λ_o the patch's projected
solid angle, so that Σ_o f_io Λ_o is the incidence's hemispherical reflectance or
transmittance (m/N of the same rays, exactly).

**Certificate.** Every patch fraction m_io/N_i of the file — all four matrices, every
wavelength — and every hemispherical R and T is within ε of its true value at once with
probability ≥ 1 − δ: N_i = ⌈ln(2S/δ)/(2ε²)⌉ rays per incidence for the S statements
(Hoeffding + union, :func:`virtspec_mi.budgets.binomial.union_hoeffding_rays`); the
sidecar (NetCDF) holds the counts, fractions, the patch values with their simultaneous
Clopper–Pearson bounds (each at δ/S) and the statement.

**Orientation.** WINDOW's "front" is the specimen's front (its +z side, the side the
instrument lights); "Transmission Front" is light incident on the front, leaving
through the back. Radiance reverses WINDOW's front and back (its +Z points into the
room, ``bsdf.h``): a reader querying Radiance for our front incidence (θ, φ_source)
asks for (180° − θ, φ_source). The data are written ``IncidentDataStructure Columns``:
one row per outgoing patch, one column per incident patch (Radiance's ``bsdf_m.c``).

Several wavelengths: Radiance reads only the photopic ``Visible`` block (and CIE-X,
CIE-Z); it is written as the D65 × ȳ weighted average of the wavelengths measured (a
quadrature of the photopic integral on those wavelengths, ASTM E308 weights through
colour-science), each wavelength also in a block of its own
(``<Wavelength unit="Nanometer">``), which Radiance skips. One wavelength: ``Visible``
holds it (the file says so in a comment).

References
----------
Klems, J.H. (1994). ASHRAE Transactions 100(1), 1065–1072 (the basis and matrices).
Ward, G. et al. The Radiance BSDF library, ``ray/src/common/bsdf_m.c`` and ``bsdf.h``
(the XML layout read by Radiance). Nicodemus, F.E. et al. (1977). NBS Monograph 160
(projected solid angle). Hoeffding, W. (1963). JASA 58, 13–30. Clopper, C.J., Pearson,
E.S. (1934). Biometrika 26, 404–413.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field, replace
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, ClassVar, Mapping, Sequence
from xml.sax.saxutils import escape

import numpy as np

from virtspec_mi.base.version import __version__
from virtspec_mi.exchange.common import check_companions
from virtspec_mi.base.files import atomic_write, same_file
from virtspec_mi.exchange.klems_basis import KlemsBasis, klems_basis
from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.results.integrity import CountRules, field_value, finite_labels, whole_counts
from virtspec_mi.results.records import Record

__all__ = ["SIDES", "KINDS", "KlemsMeasurement", "klems_from_gonio", "write_klems", "aggregate", "check_escaped", "read_klems",
           "read_klems_sidecar", "sidecar_path", "check_klems", "check_klems_output", "photopic_weights"]

SIDES: tuple[str, ...] = ("front", "back")
"""Sides of incidence: the specimen's front (+z, lit by the instrument) and its back."""

KINDS: tuple[str, ...] = ("reflection", "transmission")
"""Scattering kinds: back to the side of incidence, or through the layer."""

_DIRECTIONS = {("front", "reflection"): "Reflection Front", ("front", "transmission"): "Transmission Front",
               ("back", "reflection"): "Reflection Back", ("back", "transmission"): "Transmission Back"}


_INCIDENCE_RULES = CountRules("rays", parts={"reflected": "rays", "transmitted": "rays"},
                              sums=((("reflected", "transmitted"), "rays", False),))
"""Each incidence's R and T counts within its rays."""


@dataclass(frozen=True, eq=False)
class KlemsMeasurement(Record):
    """
    Klems matrices with their exact counts and certificate (see the module docstring); a
    result kind (format ``"virtspec-mi klems 1"``): its Dataset is the sidecar (counts,
    fractions, f with its simultaneous bounds, R and T, the patches), its files the
    ``.nc`` sidecar and ``.json``, its export the Klems XML (``.xml``, which
    :func:`virtspec_mi.read_result` reads through its sidecar).

    Attributes
    ----------
    basis : KlemsBasis
        The angle basis (incidence and outgoing).
    sides : tuple of str
        ``("front",)`` or ``("front", "back")``.
    wavelengths : ndarray
        Wavelengths (nm).
    counts : ndarray
        int64, (side, wavelength, incidence patch, kind, outgoing patch): rays of each
        incidence that left into each outgoing patch (kind 0 reflection, 1 transmission).
    rays : ndarray
        int64, (side, wavelength, incidence): N per incidence.
    reflected, transmitted : ndarray
        int64, (side, wavelength, incidence): the instrument's R and T counts.
    epsilon, delta : float
        Every patch fraction and every R, T within ε, all at once with probability ≥ 1 − δ.
    isotropic : bool
        The incidences of each ring are the ring's one reading rotated (a rotation-invariant
        specimen), not one reading each.
    provenance : dict
        Scene, seed, versions, time, rays.
    """

    FORMAT: ClassVar[str] = "virtspec-mi klems 1"
    KIND: ClassVar[str] = "Klems measurement"
    VARIABLES: ClassVar[dict[str, tuple[str, str]]] = {
        "side": ("1", "side of incidence (front: the specimen's +z)"), "kind": ("1", "reflection or transmission"),
        "incidence": ("1", "incident Klems patch"), "outgoing": ("1", "outgoing Klems patch"),
        "patch": ("1", "Klems patch"), "counts": ("1", "rays of the incidence that left into the outgoing patch"),
        "fraction": ("1", "patch fraction m/N"), "bsdf": ("1/sr", "patch BSDF f = (m/N)/Lambda"),
        "bsdf_lower": ("1/sr", "simultaneous Clopper-Pearson lower bound of f (each at delta/S)"),
        "bsdf_upper": ("1/sr", "simultaneous Clopper-Pearson upper bound of f (each at delta/S)"),
        "reflectance": ("1", "hemispherical reflectance of the incidence"),
        "transmittance": ("1", "hemispherical transmittance of the incidence"),
        "reflectance_lower": ("1", "Clopper-Pearson lower bound of the reflectance (at delta/S)"),
        "reflectance_upper": ("1", "Clopper-Pearson upper bound of the reflectance (at delta/S)"),
        "transmittance_lower": ("1", "Clopper-Pearson lower bound of the transmittance (at delta/S)"),
        "transmittance_upper": ("1", "Clopper-Pearson upper bound of the transmittance (at delta/S)"),
        "certified_epsilon": ("1", "tolerance the incidence's rays give every statement at delta/S (Hoeffding)"),
        "theta": ("degree", "polar angle of the patch centre"), "phi": ("degree", "azimuth of the patch centre"),
        "theta_lower": ("degree", "lower polar bound of the patch's ring"),
        "theta_upper": ("degree", "upper polar bound of the patch's ring"),
        "projected_solid_angle": ("sr", "projected solid angle of the patch (Lambda)"),
    }

    basis: KlemsBasis
    sides: tuple[str, ...]
    wavelengths: np.ndarray = field()
    counts: np.ndarray
    rays: np.ndarray
    reflected: np.ndarray
    transmitted: np.ndarray
    epsilon: float
    delta: float = field()
    isotropic: bool = False
    provenance: dict[str, Any] = field(default_factory=dict)

    @property
    def statements(self) -> int:
        """S: patch fractions (two matrices per side) plus R and T, per wavelength and incidence."""

        return int(self.rays.size * (2 * self.basis.size + 2))

    @property
    def fraction(self) -> np.ndarray:
        """m_io/N_i, shape of :attr:`counts`."""

        return self.counts / self.rays[..., None, None]

    @property
    def bsdf(self) -> np.ndarray:
        """f_io = (m_io/N_i)/Λ_o (sr⁻¹), shape of :attr:`counts`."""

        return self.fraction / self.basis.projected_solid_angle

    @property
    def reflectance(self) -> np.ndarray:
        return self.reflected / self.rays

    @property
    def transmittance(self) -> np.ndarray:
        return self.transmitted / self.rays

    @property
    def certified_epsilon(self) -> np.ndarray:
        """The tolerance the rays of each incidence give every statement at δ/S (Hoeffding)."""

        return np.sqrt(np.log(2.0 * self.statements / self.delta) / (2.0 * self.rays))

    def bsdf_band(self) -> tuple[np.ndarray, np.ndarray]:
        """Simultaneous Clopper–Pearson bounds of f_io (each at δ/S), shape of :attr:`counts`."""

        lower, upper = clopper_pearson(self.counts, self.rays[..., None, None], self.delta / self.statements)
        lam = self.basis.projected_solid_angle
        return lower / lam, upper / lam

    def statement(self) -> str:
        worst = float(np.max(self.certified_epsilon))
        kind = "rotated readings of an isotropic specimen" if self.isotropic else "one reading per incidence"
        return (f"every patch fraction m/N of the {2 * len(self.sides)} matrices and every hemispherical R, T "
                f"({self.statements:,} statements, {self.rays.size:,} incidences, {kind}) within {worst:.3g} of its "
                f"true value at once with probability >= {1 - self.delta:g} (Hoeffding + union)")

    def visible(self) -> tuple[np.ndarray, np.ndarray]:
        """
        Photopic ``Visible`` values: (f of shape (side, incidence, kind, outgoing), weights
        per wavelength) — the D65 × ȳ weighted average of the wavelengths measured, or the
        one wavelength.
        """

        if len(self.wavelengths) == 1:
            return self.bsdf[:, 0], np.ones(1)
        weights = photopic_weights(self.wavelengths)
        return np.tensordot(weights, np.moveaxis(self.bsdf, 1, 0), axes=1), weights

    # -- files ------------------------------------------------------------------------

    def xml(self, name: str = "virtspec-mi specimen") -> str:
        """The WINDOW 6 style Klems XML text (see the module docstring)."""

        basis = self.basis
        visible, weights = self.visible()
        prov = self.provenance
        out = ['<?xml version="1.0" encoding="UTF-8"?>',
               '<WindowElement xmlns="http://windows.lbl.gov" xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" '
               'xsi:schemaLocation="http://windows.lbl.gov/BSDF-v1.4.xsd">',
               "<!-- Made by virtspec-mi (a virtual goniophotometer): " + escape(self.statement()).replace("--", "- -"),
               f"     rays per incidence {int(self.rays.min()):,} to {int(self.rays.max()):,}; Mitsuba "
               f"{prov.get('mitsuba')}, virtspec-mi {prov.get('virtspec_mi')}, {prov.get('created')}; scene "
               f"{prov.get('scene')}; certified bounds per patch in the NetCDF sidecar {prov.get('sidecar', '')}",
               "     Visible = " + ("the one wavelength measured, "
                                    f"{self.wavelengths[0]:g} nm (monochromatic, not a photopic integral)"
                                    if len(self.wavelengths) == 1 else
                                    "D65 x ybar weighted average of " + ", ".join(
                                        f"{w:g} nm ({v:.4f})" for w, v in zip(self.wavelengths, weights)))
               + " -->",
               "<WindowElementType>System</WindowElementType>",
               "<FileType>BSDF</FileType>",
               "<Optical>",
               "<Layer>",
               "\t<Material>",
               f"\t\t<Name>{escape(name)}</Name>",
               "\t\t<Manufacturer>virtspec-mi (simulated)</Manufacturer>",
               "\t\t<DeviceType>Other</DeviceType>",
               "\t</Material>",
               "\t<DataDefinition>",
               "\t\t<IncidentDataStructure>Columns</IncidentDataStructure>",
               "\t\t<AngleBasis>",
               f"\t\t\t<AngleBasisName>{basis.name}</AngleBasisName>"]
        for ring in range(len(basis.phis)):
            out += ["\t\t\t<AngleBasisBlock>",
                    f"\t\t\t\t<Theta>{basis.theta_centres[ring]:g}</Theta>",
                    f"\t\t\t\t<nPhis>{int(basis.phis[ring])}</nPhis>",
                    "\t\t\t\t<ThetaBounds>",
                    f"\t\t\t\t\t<LowerTheta>{basis.lower[ring]:g}</LowerTheta>",
                    f"\t\t\t\t\t<UpperTheta>{basis.upper[ring]:g}</UpperTheta>",
                    "\t\t\t\t</ThetaBounds>",
                    "\t\t\t</AngleBasisBlock>"]
        out += ["\t\t</AngleBasis>", "\t</DataDefinition>"]
        blocks = [("Visible", 'unit="Integral"', visible)]
        if len(self.wavelengths) > 1:
            blocks += [(f"{w:g}", 'unit="Nanometer"', self.bsdf[:, i]) for i, w in enumerate(self.wavelengths)]
        for label, unit, values in blocks:
            out += ["\t<WavelengthData>",
                    "\t\t<LayerNumber>System</LayerNumber>",
                    f"\t\t<Wavelength {unit}>{label}</Wavelength>",
                    "\t\t<SourceSpectrum>CIE Illuminant D65 1nm.ssp</SourceSpectrum>",
                    "\t\t<DetectorSpectrum>ASTM E308 1931 Y.dsp</DetectorSpectrum>"]
            for s, side in enumerate(self.sides):
                for k, kind in enumerate(KINDS):
                    matrix = values[s, :, k, :]  # (incidence, outgoing)
                    rows = "\n".join(", ".join(f"{v:.9g}" for v in matrix[:, o]) for o in range(basis.size))
                    out += ["\t\t<WavelengthDataBlock>",
                            f"\t\t\t<WavelengthDataDirection>{_DIRECTIONS[side, kind]}</WavelengthDataDirection>",
                            f"\t\t\t<ColumnAngleBasis>{basis.name}</ColumnAngleBasis>",
                            f"\t\t\t<RowAngleBasis>{basis.name}</RowAngleBasis>",
                            f"\t\t\t<ScatteringDataType>{'BRDF' if kind == 'reflection' else 'BTDF'}"
                            "</ScatteringDataType>",
                            "\t\t\t<ScatteringDataFormat>MatrixData</ScatteringDataFormat>",
                            "\t\t\t<ScatteringData>", rows, "\t\t\t</ScatteringData>",
                            "\t\t</WavelengthDataBlock>"]
            out.append("\t</WavelengthData>")
        out += ["</Layer>", "</Optical>", "</WindowElement>", ""]
        return "\n".join(out)

    def _stored(self) -> Any:
        """The sidecar: counts, fractions, f with its simultaneous bounds, R and T, certificate."""

        import xarray as xr

        b = self.basis
        dims = ("side", "wavelength", "incidence", "kind", "outgoing")
        lower, upper = self.bsdf_band()
        r_lo, r_hi = clopper_pearson(self.reflected, self.rays, self.delta / self.statements)
        t_lo, t_hi = clopper_pearson(self.transmitted, self.rays, self.delta / self.statements)
        patch = {"theta": ("patch", b.theta), "phi": ("patch", b.phi),
                 "theta_lower": ("patch", b.lower[b.ring]), "theta_upper": ("patch", b.upper[b.ring]),
                 "projected_solid_angle": ("patch", b.projected_solid_angle)}
        data = {"counts": (dims, self.counts), "fraction": (dims, self.fraction), "bsdf": (dims, self.bsdf),
                "bsdf_lower": (dims, lower), "bsdf_upper": (dims, upper),
                "rays": (dims[:3], self.rays), "reflected": (dims[:3], self.reflected),
                "transmitted": (dims[:3], self.transmitted), "reflectance": (dims[:3], self.reflectance),
                "transmittance": (dims[:3], self.transmittance), "reflectance_lower": (dims[:3], r_lo),
                "reflectance_upper": (dims[:3], r_hi), "transmittance_lower": (dims[:3], t_lo),
                "transmittance_upper": (dims[:3], t_hi), "certified_epsilon": (dims[:3], self.certified_epsilon),
                **patch}
        coords = {"side": list(self.sides), "wavelength": self.wavelengths, "kind": list(KINDS),
                  "incidence": np.arange(b.size), "outgoing": np.arange(b.size), "patch": np.arange(b.size)}
        attrs = {"basis": b.key, "basis_name": b.name, "epsilon": self.epsilon,
                 "delta": self.delta, "statements": self.statements, "isotropic": int(self.isotropic),
                 "certificate": self.statement(), "provenance": json.dumps(self.provenance, sort_keys=True),
                 "orientation": "front = specimen +z (WINDOW front); incident patch (theta, phi): source at azimuth "
                                "phi + 180 deg; outgoing patch (theta, phi) at azimuth phi; transmitted theta from -z"}
        return xr.Dataset(data, coords=coords, attrs=attrs)

    @classmethod
    def _from_legacy(cls, dataset: Any) -> "KlemsMeasurement":
        """A sidecar written before the result family (its counts as variables, its settings as attributes)."""

        try:
            return cls(klems_basis(str(dataset.attrs["basis"])), tuple(str(s) for s in dataset["side"].values),
                       finite_labels(dataset["wavelength"].values, "wavelength"),
                       whole_counts(dataset["counts"].values, "counts"), whole_counts(dataset["rays"].values, "rays"),
                       whole_counts(dataset["reflected"].values, "reflected"),
                       whole_counts(dataset["transmitted"].values, "transmitted"),
                       float(dataset.attrs["epsilon"]), float(dataset.attrs["delta"]), bool(dataset.attrs["isotropic"]),
                       json.loads(str(dataset.attrs["provenance"])))
        except KeyError as error:
            raise ValueError(f"lacks the field {error} of a Klems sidecar") from None

    def as_dict(self) -> dict[str, Any]:
        """The matrices as plain data: basis, sides, wavelengths, the exact counts, ε, δ, provenance, the certificate."""

        return {"format": self.FORMAT, "basis": self.basis.key, "sides": list(self.sides),
                "wavelengths": self.wavelengths.tolist(), "counts": self.counts.tolist(), "rays": self.rays.tolist(),
                "reflected": self.reflected.tolist(), "transmitted": self.transmitted.tolist(),
                "epsilon": self.epsilon, "delta": self.delta, "isotropic": bool(self.isotropic),
                "provenance": self.provenance, "certificate": self.statement()}

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any]) -> "KlemsMeasurement":
        return cls(klems_basis(field_value(data, "basis", "text")), tuple(data["sides"]),
                   finite_labels(data["wavelengths"], "wavelengths"), whole_counts(data["counts"], "counts"),
                   whole_counts(data["rays"], "rays"), whole_counts(data["reflected"], "reflected"),
                   whole_counts(data["transmitted"], "transmitted"), float(data["epsilon"]), float(data["delta"]),
                   field_value(data, "isotropic", "flag"), field_value(data, "provenance", "object"))

    def _check(self) -> None:
        """Shapes by the basis, sides and wavelengths; each incidence's counts within its rays; the patches add up."""

        size = self.basis.size
        expected = (len(self.sides), len(self.wavelengths), size)
        for name, values in (("rays", self.rays), ("reflected", self.reflected), ("transmitted", self.transmitted)):
            if np.shape(values) != expected:
                raise ValueError(f"'{name}' has shape {np.shape(values)}; the sides, wavelengths and the "
                                 f"{self.basis.name} basis give {expected}")
        if np.shape(self.counts) != expected + (2, size):
            raise ValueError(f"'counts' has shape {np.shape(self.counts)}; expected {expected + (2, size)}")
        super()._check()
        if np.any(self.counts[..., 0, :].sum(-1) > self.reflected) or \
                np.any(self.counts[..., 1, :].sum(-1) > self.transmitted):
            raise ValueError("'counts' add up to more than the reflected or transmitted rays of an incidence")

    def _count_groups(self) -> list[tuple[str, Any, CountRules, tuple[str, ...]]]:
        counts = {"rays": self.rays, "reflected": self.reflected, "transmitted": self.transmitted}
        return [("", counts, _INCIDENCE_RULES, ("side", "wavelength", "incidence"))]

    def _check_stored(self, data: Mapping[str, Any]) -> None:
        if "certificate" in data and data["certificate"] != self.statement():
            raise ValueError("'certificate' disagrees with the counts it is made from (edited?)")

    def write(self, path: str | os.PathLike, name: str = "virtspec-mi specimen", overwrite: bool = False) -> Path:
        """
        Write by the one writer (:meth:`ResultBase.write <virtspec_mi.results.base.ResultBase.write>`):
        ``.nc`` (the sidecar alone) or ``.json``, or its export ``.xml``: the Klems XML to
        ``path`` and the certified sidecar to the same name with ``.nc`` (:func:`sidecar_path`),
        both atomically. The sidecar replaces a file of its name only when that is a Klems
        sidecar or with ``overwrite=True`` (:func:`check_klems_output`).
        """

        if Path(path).suffix.lower() == ".xml":
            return super().write(path, name=name, overwrite=overwrite)
        return super().write(path)


def _write_xml(measured: KlemsMeasurement, path: Path, name: str = "virtspec-mi specimen",
               overwrite: bool = False) -> Path:
    """The Klems XML file and its sidecar (:meth:`KlemsMeasurement.write`)."""

    check_klems_output(path, overwrite=overwrite)
    sidecar = sidecar_path(path)
    measured = replace(measured, provenance={**measured.provenance, "sidecar": sidecar.name})
    atomic_write(sidecar, lambda tmp: measured.to_dataset().to_netcdf(tmp))
    atomic_write(path, lambda tmp: Path(tmp).write_text(measured.xml(name), encoding="utf-8"))
    return path


def sidecar_path(path: str | os.PathLike) -> Path:
    """The NetCDF sidecar of a Klems XML file: the same name with ``.nc``."""

    return Path(path).with_suffix(".nc")


KlemsMeasurement.EXPORTS = {".xml": _write_xml}
KlemsMeasurement.COMPANIONS = {".xml": sidecar_path}



def photopic_weights(wavelengths: Sequence[float]) -> np.ndarray:
    """
    The D65 × ȳ weights (summing to 1) of the photopic ``Visible`` block on several
    ``wavelengths``; ``ValueError`` when none of them carries photopic weight.
    """

    import colour

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    lam = np.asarray(wavelengths, dtype=np.float64)
    ybar = np.interp(lam, cmfs.wavelengths, cmfs.values[:, 1], left=0.0, right=0.0)
    weights = ybar * np.interp(lam, d65.wavelengths, d65.values, left=0.0, right=0.0)
    if not weights.sum() > 0:
        raise ValueError(f"wavelengths {', '.join(f'{w:g}' for w in lam)} nm carry no photopic weight (a Klems "
                         "file's Visible block needs one of them within 360-830 nm, or a single wavelength)")
    return weights / weights.sum()


def check_klems_output(path: str | os.PathLike, overwrite: bool = False, inputs: Sequence[Any] = (),
                       wavelengths: Sequence[float] | None = None) -> Path:
    """
    Refuse (``ValueError``, before anything is measured) a Klems output ``path`` that
    does not end in ``.xml``, whose folder does not exist, that is one of ``inputs``
    (the scene file measured), whose sidecar ``.nc`` would replace an input or a
    file that is not a Klems sidecar (unless ``overwrite``), or whose ``wavelengths``
    (several) carry no photopic weight for its ``Visible`` block.
    """

    path = Path(path)
    if path.suffix.lower() != ".xml":
        raise ValueError(f"out must end in .xml (got {path.name!r})")
    if not path.parent.is_dir():
        raise ValueError(f"out {path}: the folder {path.parent} does not exist")
    given = [Path(item) for item in inputs if isinstance(item, (str, os.PathLike)) and Path(item).exists()]
    if any(same_file(path, item) for item in given):
        raise ValueError(f"out {path} is the scene file being measured; choose another name for the Klems file")
    check_companions(path, [sidecar_path(path)], _is_sidecar, overwrite, inputs=given)
    if wavelengths is not None and len(wavelengths) > 1:
        photopic_weights(wavelengths)
    return path


def _is_sidecar(path: Path) -> bool:
    """Whether ``path`` is a Klems sidecar written by virtspec-mi (its ``format`` attribute)."""

    try:
        import xarray as xr

        with xr.open_dataset(path) as dataset:
            return dataset.attrs.get("format") == KlemsMeasurement.FORMAT
    except Exception:  # not NetCDF, unreadable: not ours
        return False


def read_klems_sidecar(path: str | os.PathLike) -> KlemsMeasurement:
    """
    The :class:`KlemsMeasurement` of a sidecar written by :meth:`KlemsMeasurement.write` (or of
    its Klems XML file): :func:`virtspec_mi.read_result` that refuses another kind.
    """

    from virtspec_mi.base.files import read_netcdf

    path = Path(path)
    if path.suffix.lower() == ".nc":
        read_netcdf(path, "Klems sidecar")  # a file that is not NetCDF, named as a sidecar's
    return KlemsMeasurement.read(path)


# ------------------------------------------------------------------------------ aggregation

def aggregate(reading: Any, basis: KlemsBasis, shifts: Sequence[int] | None = None) -> np.ndarray:
    """
    Patch counts of a goniophotometer reading, (wavelength, θi, kind, outgoing); with
    ``shifts`` (φ bins per θi), each θi's bins rotated by that many bins first. Exact:
    integer counts summed per patch (float64 sums of integers below 2⁵³).
    """

    bins = reading.bins
    if bins.fold_phi:
        raise ValueError("a folded goniophotometer reading (fold_phi) cannot be written on a Klems basis")
    counts = np.asarray(reading.bin_counts, dtype=np.int64)
    if shifts is not None:
        counts = np.stack([np.roll(counts[:, i], int(s), axis=-1) for i, s in enumerate(shifts)], axis=1)
    tables = [basis.aggregation(bins.theta_edges, bins.phi_edges, transmitted).ravel() for transmitted in (False, True)]
    flat = counts.reshape(counts.shape[:2] + (-1,)).astype(np.float64)
    out = np.zeros(counts.shape[:2] + (2, basis.size), dtype=np.int64)
    for k, table in enumerate(tables):
        keep = np.nonzero(table >= 0)[0]
        for row in np.ndindex(*counts.shape[:2]):
            sums = np.bincount(table[keep], weights=flat[row][keep], minlength=basis.size)
            out[row + (k,)] = np.rint(sums).astype(np.int64)
    return out


def check_escaped(patch_counts: np.ndarray, reflected: np.ndarray, transmitted: np.ndarray) -> None:
    if not (np.array_equal(patch_counts[..., 0, :].sum(-1), reflected)
            and np.array_equal(patch_counts[..., 1, :].sum(-1), transmitted)):
        raise ValueError("the goniophotometer bins do not cover both hemispheres: the Klems patches must add up to "
                         "the reflected and transmitted counts")


def klems_from_gonio(front: Any, back: Any = None, basis: str = "full", isotropic: bool = False,
                     epsilon: float | None = None) -> KlemsMeasurement:
    """
    Klems matrices from goniophotometer readings taken on bins that nest in the basis.

    Parameters
    ----------
    front, back
        :class:`~virtspec_mi.instruments.goniophotometer.result.GonioResult` of the front (and, optionally, of the
        back) side: θi must include every ring centre of the basis, θo edges every ring
        bound in both hemispheres, φo a uniform grid with every patch boundary on an edge
        (:meth:`KlemsBasis.phi_bins`), not folded. A reading holds one φi: its rings'
        other incidences are filled by rotating it, which is right only for a specimen
        invariant under rotation about its normal — say so with ``isotropic=True``
        (:func:`virtspec_mi.applications.klems.measure.klems_measure` measures every incidence
        instead).
    basis
        ``full``, ``half`` or ``quarter``.
    epsilon
        The ε the rays were sized for (default: what they give, :attr:`certified_epsilon`).
    """

    klems = klems_basis(basis)
    if not isotropic:
        raise ValueError("a goniophotometer reading holds one phi_i: pass isotropic=True for a specimen invariant "
                         "under rotation about its normal (each ring's incidences are then the reading rotated), or "
                         "measure every incidence with virtspec_mi.applications.klems.measure.klems_measure")
    readings = [front] + ([] if back is None else [back])
    side_counts, rays, refl, trans = [], [], [], []
    for reading in readings:
        theta_i = np.atleast_1d(reading.theta_i)
        pick = []
        for centre in klems.theta_centres:
            hit = np.nonzero(np.isclose(theta_i, centre, atol=1e-9))[0]
            if hit.size == 0:
                raise ValueError(f"theta_i must include every ring centre of the {klems.name} basis "
                                 f"({', '.join(f'{t:g}' for t in klems.theta_centres)}); {centre:g} is missing")
            pick.append(int(hit[0]))
        width = 360.0 / (len(reading.bins.phi_edges) - 1)
        shifts_all = []
        for p in range(klems.size):
            turn = (klems.phi[p] + 180.0 - reading.phi_i) % 360.0
            shift = turn / width
            if not np.isclose(shift, round(shift), atol=1e-9):
                raise ValueError(f"phi_i = {reading.phi_i:g} and {len(reading.bins.phi_edges) - 1} phi_o bins do not "
                                 "turn onto every Klems incidence azimuth by whole bins")
            shifts_all.append(int(round(shift)))
        columns = [pick[klems.ring[p]] for p in range(klems.size)]
        base = aggregate(_Rotated(reading, columns, shifts_all), klems)
        r = np.asarray(reading.result.reflected)[:, columns]
        t = np.asarray(reading.result.transmitted)[:, columns]
        check_escaped(base, r, t)
        side_counts.append(base)
        rays.append(np.asarray(reading.rays)[:, columns])
        refl.append(r)
        trans.append(t)
    counts = np.stack(side_counts)
    rays_arr = np.stack(rays)
    result = KlemsMeasurement(klems, SIDES[:len(readings)], np.asarray(front.wavelengths, dtype=np.float64), counts,
                              rays_arr, np.stack(refl), np.stack(trans), 0.0, float(front.delta), True,
                              {"virtspec_mi": __version__, "scene": front.result.scene, "source": "GonioResult",
                               "mitsuba": _installed_mitsuba(),
                               "created": datetime.now(timezone.utc).isoformat(timespec="seconds")})
    eps = float(np.max(result.certified_epsilon)) if epsilon is None else float(epsilon)
    return replace(result, epsilon=eps)


def _installed_mitsuba() -> str:
    """The Mitsuba version installed now, labelled so (a GonioResult does not record the one that traced it)."""

    try:
        import mitsuba
    except ImportError:  # pragma: no cover - the package needs Mitsuba
        return "unknown (not installed)"
    return f"{mitsuba.__version__} (installed when this file was made from the reading)"


@dataclass(frozen=True)
class _Rotated:
    """A reading's θi columns picked and each φ-rotated (for :func:`aggregate`)."""

    reading: Any
    columns: list[int]
    shifts: list[int]

    @property
    def bins(self) -> Any:
        return self.reading.bins

    @property
    def bin_counts(self) -> np.ndarray:
        counts = np.asarray(self.reading.bin_counts)[:, self.columns]
        return np.stack([np.roll(counts[:, i], s, axis=-1) for i, s in enumerate(self.shifts)], axis=1)


# ------------------------------------------------------------------------------ reading back

def read_klems(path: str | os.PathLike) -> dict[str, Any]:
    """
    The matrices of a Klems XML file, read with the standard library's XML parser (not
    the code that wrote it): ``{"basis": name, "blocks": {(wavelength, direction):
    ndarray (incidence, outgoing)}}`` (``IncidentDataStructure`` ``Columns`` or ``Rows``).

    Raises
    ------
    ValueError
        For a file that is not WINDOW BSDF XML, an unknown basis, or a matrix of the
        wrong size.
    """

    import xml.etree.ElementTree as ET

    from virtspec_mi.exchange.klems_basis import BASES

    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as error:
        raise ValueError(f"{path}: not well-formed XML ({error})") from None
    ns = {"w": root.tag[1:].split("}")[0]} if root.tag.startswith("{") else {"w": ""}

    def find(node: Any, tag: str) -> Any:
        return node.find(f"w:{tag}", ns) if ns["w"] else node.find(tag)

    def find_all(node: Any, tag: str) -> list[Any]:
        return node.findall(f"w:{tag}", ns) if ns["w"] else node.findall(tag)

    layer = find(find(root, "Optical"), "Layer") if find(root, "Optical") is not None else None
    if layer is None:
        raise ValueError(f"{path}: no Optical/Layer element (not a WINDOW BSDF file)")
    definition = find(layer, "DataDefinition")
    structure = (find(definition, "IncidentDataStructure").text or "").strip()
    sizes = {name: sum(n for _, n in rings) for name, rings in BASES.values()}
    blocks: dict[tuple[str, str], np.ndarray] = {}
    for data in find_all(layer, "WavelengthData"):
        wavelength = (find(data, "Wavelength").text or "").strip()
        for block in find_all(data, "WavelengthDataBlock"):
            direction = (find(block, "WavelengthDataDirection").text or "").strip()
            column = (find(block, "ColumnAngleBasis").text or "").strip()
            row = (find(block, "RowAngleBasis").text or "").strip()
            if column not in sizes or row not in sizes:
                raise ValueError(f"{path}: unknown angle basis {column!r} / {row!r}")
            text = (find(block, "ScatteringData").text or "").replace(",", " ").split()
            values = np.array([float(v) for v in text], dtype=np.float64)
            n_in, n_out = sizes[column], sizes[row]
            if values.size != n_in * n_out:
                raise ValueError(f"{path}: {direction} ({wavelength}) holds {values.size} values, not {n_in} x {n_out}")
            if structure == "Columns":  # rows are outgoing patches, columns incident ones
                matrix = values.reshape(n_out, n_in).T
            elif structure == "Rows":
                matrix = values.reshape(n_in, n_out)
            else:
                raise ValueError(f"{path}: IncidentDataStructure {structure!r} is not Columns or Rows")
            blocks[wavelength, direction] = matrix
    basis = (find(find(definition, "AngleBasis"), "AngleBasisName").text or "").strip()
    return {"basis": basis, "structure": structure, "blocks": blocks}


_RADIANCE_SCRIPT = """
import json, sys
from pyradiance import bsdf
path, queries = sys.argv[1], json.loads(sys.stdin.read())
data = bsdf.load_file(path)
if data is None:
    sys.exit(3)
r, t = bsdf.SAMPLE_ALL & ~bsdf.SAMPLE_T, bsdf.SAMPLE_ALL & ~bsdf.SAMPLE_R
print(json.dumps([[bsdf.direct_hemi(data, th, ph, r), bsdf.direct_hemi(data, th, ph, t)] for th, ph in queries]))
"""


def _radiance_direct_hemi(path: Path, queries: list[tuple[float, float]]) -> np.ndarray:
    """
    Radiance's SDdirectHemi (reflection, transmission) at each incident (θ, φ) in Radiance's
    frame, in a child process: the library may crash on a malformed file, which must not
    take the caller with it.
    """

    import subprocess
    import sys

    try:
        import pyradiance  # noqa: F401  (fail here, clearly, when the reader is missing)
    except ImportError as error:
        raise ImportError(f"reader='pyradiance' needs the pyradiance package ({error})") from None
    run = subprocess.run([sys.executable, "-c", _RADIANCE_SCRIPT, str(path)], input=json.dumps(queries),
                         capture_output=True, text=True)
    if run.returncode != 0:
        detail = run.stderr.strip().splitlines()
        reason = detail[-1] if detail and run.returncode != 3 else "a format error"
        if run.returncode < 0:
            reason = f"the library crashed (signal {-run.returncode})"
        raise ValueError(f"{path}: Radiance cannot read it ({reason})")
    return np.array(json.loads(run.stdout), dtype=np.float64)


def check_klems(path: str | os.PathLike, sidecar: str | os.PathLike | None = None,
                reader: str = "pyradiance") -> dict[str, Any]:
    """
    Read a Klems file back with an independent reader and hold each incidence's
    hemispherical sums to the certified R and T of the sidecar.

    Parameters
    ----------
    path
        The Klems XML file.
    sidecar
        Its NetCDF sidecar (default: :func:`sidecar_path`).
    reader
        ``pyradiance`` (Radiance's own BSDF library, ``SDdirectHemi`` through the
        ``pyradiance`` package, in a child process: the library may crash on a malformed
        file) or ``xml`` (:func:`read_klems`, the standard library's parser, summing f·Λ).

    Returns
    -------
    dict
        ``worst`` (largest |sum − certified value|), ``tolerance`` (the certified ε of
        the worst incidence), ``checked`` (sums compared) and ``passed``.

    Raises
    ------
    ValueError
        When the reader cannot parse the file (a corrupted file), or a sum falls outside
        the certificate (a swapped or altered matrix).
    """

    measured = read_klems_sidecar(sidecar if sidecar is not None else sidecar_path(path))
    basis = measured.basis
    visible, _ = measured.visible()
    lam = basis.projected_solid_angle
    expected = (visible * lam).sum(-1)  # (side, incidence, kind): the certified R and T (Visible)
    tolerance = float(np.max(measured.certified_epsilon))
    found = np.full(expected.shape, np.nan)
    if reader == "pyradiance":
        queries = []
        for side in measured.sides:
            for i in range(basis.size):
                # Radiance's +Z is WINDOW's back: our front incidence (theta, source azimuth) is 180 - theta there
                theta = 180.0 - float(basis.theta[i]) if side == "front" else float(basis.theta[i])
                queries.append((theta, float((basis.phi[i] + 180.0) % 360.0)))
        found = _radiance_direct_hemi(Path(path), queries).reshape(found.shape)
    elif reader == "xml":
        blocks = read_klems(path)["blocks"]
        for s, side in enumerate(measured.sides):
            for k, kind in enumerate(KINDS):
                matrix = blocks.get(("Visible", _DIRECTIONS[side, kind]))
                if matrix is None:
                    raise ValueError(f"{path}: no {_DIRECTIONS[side, kind]} block")
                found[s, :, k] = (matrix * lam[None, :]).sum(-1)
    else:
        raise ValueError(f"reader must be 'pyradiance' or 'xml' (got {reader!r})")
    worst = float(np.nanmax(np.abs(found - expected)))
    report = {"worst": worst, "tolerance": tolerance, "checked": int(found.size), "passed": worst < tolerance}
    if not report["passed"]:
        raise ValueError(f"{path}: a hemispherical sum read back differs from the certified R/T by {worst:.4g} >= "
                         f"{tolerance:.4g} (swapped, altered or foreign matrices)")
    return report


def write_klems(front: Any, path: str | os.PathLike, back: Any = None, basis: str = "full", isotropic: bool = False,
                overwrite: bool = False) -> Path:
    """
    Write the WINDOW 6 Klems XML (and its NetCDF sidecar) of goniophotometer readings taken
    on bins that nest in the basis (:func:`klems_from_gonio`): ``vm.write_klems(reading,
    "sample.xml", basis="quarter", isotropic=True)``. The sidecar replaces no other file of
    its name unless ``overwrite=True``; the path is checked before anything is computed.
    """

    check_klems_output(path, overwrite=overwrite)
    return klems_from_gonio(front, back, basis, isotropic).write(path, overwrite=overwrite)

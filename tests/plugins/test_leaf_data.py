"""NPSG leaf data: files, units, the mesophyll absorption coefficient, spectral lookup."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from virtspec_mi.plugins import leaf_data
from virtspec_mi.plugins.leaf_data import (
    ENV_VAR,
    SHIPPED,
    GRID,
    LEAF_DATA_FILES,
    grid_lookup,
    load_leaf_data,
    mesophyll_absorption,
)

SOYBEAN_CONCENTRATIONS = dict(chlorophyll_a=3.9775, chlorophyll_b=1.1613, carotenoids=1.1323,
                              protein=78.7059, cellulose=37.7565, lignin=10.7441)
D_M = 0.5 * 1.66e-4
ROOT = Path(__file__).resolve().parents[2]

# Mesophyll absorption of the soybean defaults (the NPSG C++ reference's step lookup over the shipped
# NPSG data, Baranoski & Eng 2007, eqs. 1-3), m^-1:
# λ, α_chl, α_car, α_prot, α_cel+lig, μ_w, α total, α·d_m (values printed to 3-4 digits).
ALPHA_TABLE = [
    (400, 37720, 2960, 78.4, 21.2, 0.0066, 40778, 3.385),
    (465, 22350, 6367, 78.4, 21.2, 0.010, 28820, 2.392),
    (550, 6064, 688, 78.4, 21.2, 0.057, 6852, 0.569),
    (605, 10170, 400, 78.4, 21.2, 0.258, 10675, 0.886),
    (680, 20710, 394, 78.4, 21.2, 0.465, 21204, 1.760),
    (800, 0, 0, 79.0, 21.9, 2.03, 102.9, 0.0085),
    (1450, 0, 0, 68.4, 55.0, 3090, 3213, 0.267),
    (1940, 0, 0, 231, 38.5, 11830, 12100, 1.004),
    (2200, 0, 0, 380, 121, 1940, 2441, 0.203),
]


def close(value: float, printed: float) -> bool:
    """Agreement with a value printed to 3 significant digits (or rounded to its last digit)."""

    return abs(value - printed) <= max(5e-3 * abs(printed), 1e-3)


@pytest.fixture(scope="module")
def data(leaf_data_dir):
    return load_leaf_data(leaf_data_dir)


def test_files_load_on_the_5nm_grid(data):
    assert GRID[0] == 400 and GRID[-1] == 2500 and GRID.size == 421
    for quantity in LEAF_DATA_FILES:
        values = getattr(data, quantity)
        assert values.shape == (421,) and np.all(np.isfinite(values)) and np.all(values >= 0)
    # refractive indices of the shipped NPSG data: cuticle 1.540 @400, mesophyll 1.424 @400, antidermal 1.371 @2500
    assert abs(data.n_cuticle[0] - 1.540) < 5e-4
    assert abs(data.n_mesophyll[0] - 1.424) < 5e-4
    assert abs(data.n_antidermal[-1] - 1.371) < 5e-4


@pytest.mark.parametrize("row", ALPHA_TABLE, ids=lambda r: f"{r[0]}nm")
def test_absorption_coefficient_matches_the_table(data, row):
    wavelength, chl, car, prot, cel, water, total, optical = row
    j = int(np.flatnonzero(GRID == wavelength)[0])
    c = SOYBEAN_CONCENTRATIONS
    parts = [
        (c["chlorophyll_a"] + c["chlorophyll_b"]) * data.chlorophyll[j],
        c["carotenoids"] * data.carotenoids[j],
        c["protein"] * data.protein[j],
        (c["cellulose"] + c["lignin"]) * data.cellulose[j],
        data.water[j],
    ]
    for value, printed in zip(parts, (chl, car, prot, cel, water)):
        assert close(value, printed), (wavelength, value, printed)
    alpha = mesophyll_absorption(data, **SOYBEAN_CONCENTRATIONS)[j]
    assert close(alpha, total) and close(alpha * D_M, optical)


def test_step_lookup_reads_the_grid_value_below(data):
    alpha = mesophyll_absorption(data, **SOYBEAN_CONCENTRATIONS)
    # 551 and 608 nm read the 550 and 605 nm data (the C++ reference); 2500 is the last value
    assert np.array_equal(grid_lookup(alpha, [551.0, 608.0, 2500.0]), alpha[[30, 41, 420]])
    linear = grid_lookup(alpha, 552.5, "linear")
    assert np.isclose(linear, 0.5 * (alpha[30] + alpha[31]))
    with pytest.raises(ValueError, match="lookup must be one of step, linear"):
        grid_lookup(alpha, 551.0, "cubic")


def test_shipped_data_by_default_and_the_overrides_win(tmp_path, leaf_data_dir, monkeypatch):
    monkeypatch.delenv(ENV_VAR, raising=False)
    assert leaf_data.leaf_data_dir(None) == SHIPPED  # the package's own copy, nothing to set
    assert (SHIPPED / "LICENSE").read_text().startswith("Copyright (c) 2010, Natural Phenomena Simulation Group")
    monkeypatch.setenv(ENV_VAR, str(leaf_data_dir))
    assert leaf_data.leaf_data_dir(None) == leaf_data_dir  # the variable overrides the shipped copy


def test_the_shipped_copy_is_the_npsg_data():
    """Byte for byte the NPSG files of the reference implementation (as kept beside the checkout)."""

    source = ROOT.parent / "shared" / "data" / "abm-npsg"
    if not source.is_dir():
        pytest.skip(f"{source} (the NPSG files beside the checkout) is not here to compare with")
    for name, _, _ in LEAF_DATA_FILES.values():
        assert (SHIPPED / name).read_bytes() == (source / name).read_bytes(), name
    assert (SHIPPED / "LICENSE").read_bytes() == (source / "LICENSE").read_bytes()


def test_missing_data_names_the_files_and_where_it_looked(tmp_path, leaf_data_dir, monkeypatch):
    monkeypatch.delenv(ENV_VAR, raising=False)
    monkeypatch.setattr(leaf_data, "SHIPPED", tmp_path / "absent")
    with pytest.raises(FileNotFoundError, match="data shipped with virtspec-mi") as info:
        leaf_data.leaf_data_dir(None)
    for name, _, _ in LEAF_DATA_FILES.values():
        assert name in str(info.value)
    # a directory with one file missing: the message names that file and where it looked
    for name, _, _ in list(LEAF_DATA_FILES.values())[1:]:
        shutil.copy(leaf_data_dir / name, tmp_path / name)
    missing = next(iter(LEAF_DATA_FILES.values()))[0]
    monkeypatch.setenv(ENV_VAR, str(tmp_path))
    with pytest.raises(FileNotFoundError, match=f"lacks {missing};.*{ENV_VAR}"):
        leaf_data.leaf_data_dir(None)
    assert leaf_data.leaf_data_dir(leaf_data_dir) == leaf_data_dir  # the parameter wins over the variable


def test_malformed_file_is_refused(tmp_path, leaf_data_dir):
    for name, _, _ in LEAF_DATA_FILES.values():
        shutil.copy(leaf_data_dir / name, tmp_path / name)
    name = LEAF_DATA_FILES["water"][0]
    (tmp_path / name).write_text("1.0\n2.0\n")
    with pytest.raises(ValueError, match=f"{name}.*must hold 421 finite values"):
        load_leaf_data(tmp_path)


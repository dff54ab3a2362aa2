"""
Tests of virtspec_mi.results.figures: a result kind's figures are a table (``FIGURES``)
that ``plot`` draws from — by name, by the quantity asked, or the first — and every figure
flag of every instrument's subcommands names a figure of its result kind.
"""

from __future__ import annotations

import pytest

import virtspec_mi as vm
from result_kinds import gonio_reading, sphere_grid
from virtspec_mi.instruments import INSTRUMENTS
from virtspec_mi.results.figures import Figure, chosen_figure


def test_every_figure_flag_names_a_figure_of_its_result_kind():
    for name, instrument in INSTRUMENTS.items():
        for command in instrument.commands:
            for flag in command.all_figures():
                assert flag.figure == "" or flag.figure in instrument.result.FIGURES, (name, command.name, flag)


def test_the_figure_is_chosen_by_name_then_by_quantity_then_first():
    drawn = []
    figures = {"lobes": Figure(lambda *a: drawn.append("lobes"), "the lobes", ("brdf",)),
               "sweep": Figure(lambda *a: drawn.append("sweep"), "R, T or A", ("reflectance",))}
    assert chosen_figure(figures, "gonio", None, None) is figures["lobes"]
    assert chosen_figure(figures, "gonio", None, "reflectance") is figures["sweep"]
    assert chosen_figure(figures, "gonio", "sweep", None) is figures["sweep"]
    with pytest.raises(ValueError, match=r"figure must be one of the gonio's figures \('lobes': the lobes; 'sweep': "
                                         r"R, T or A; got 'polar'\)"):
        chosen_figure(figures, "gonio", "polar", None)
    with pytest.raises(ValueError, match="the gonio's figure 'lobes' shows brdf, not 'reflectance'"):
        chosen_figure(figures, "gonio", "lobes", "reflectance")


def test_plot_draws_each_kinds_figures(mi, tmp_path):
    gonio = gonio_reading()
    assert gonio.plot().axes[0].name == "polar"  # the first figure: the lobes
    assert gonio.plot(quantity="reflectance").axes[0].get_ylabel() == "reflectance"  # the reading's sweep
    assert len(gonio.plot(figure="series").axes) > len(gonio.plot().axes)  # one column per theta_i
    with pytest.raises(ValueError, match="quantity must be one of reflectance, transmittance, absorptance"):
        gonio.plot(quantity="reading")
    sphere = sphere_grid().isel(point=0)
    labels = [line.get_label() for line in sphere.plot(theta_i=8).axes[0].get_lines()]
    assert labels[:2] == ["reading", "hemispherical"]
    assert (tmp_path / "s.png").exists() is False and sphere.plot(tmp_path / "s.png", theta_i=8) is not None
    assert (tmp_path / "s.png").stat().st_size > 0
    with pytest.raises(ValueError, match="figure must be one of the integrating-sphere reading's figures"):
        sphere.plot(figure="polar")
    assert vm.Result.FIGURES["sweep"] is not vm.Result.FIGURES["spectra"]

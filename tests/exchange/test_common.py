"""
Tests of :mod:`virtspec_mi.exchange.common`: companion files never replace what they must not,
and derived seeds.

References
----------
Baranoski et al. (2001) (the instrument whose readings these files carry).
"""

from __future__ import annotations

import pytest

from virtspec_mi.exchange.common import check_companions, derived_seed


def never_ours(path):
    return False


def test_absent_companions_and_our_own_files_pass(tmp_path):
    output = tmp_path / "table.csv"
    check_companions(output, [tmp_path / "table.json"], never_ours)
    ours = tmp_path / "table.json"
    ours.write_text("{}")
    check_companions(output, [ours], lambda path: path == ours)


def test_a_foreign_companion_is_refused_unless_overwrite(tmp_path):
    output, foreign = tmp_path / "table.csv", tmp_path / "table.json"
    foreign.write_text("someone else's")
    with pytest.raises(ValueError, match=r"table.json already exists and was not written by virtspec-mi for this "
                                         r"output; move it, choose another output name, or pass --overwrite"):
        check_companions(output, [foreign], never_ours, flag="--overwrite")
    check_companions(output, [foreign], never_ours, overwrite=True)
    assert foreign.read_text() == "someone else's"  # checking writes nothing


def test_a_directory_is_refused_even_with_overwrite(tmp_path):
    (tmp_path / "table.json").mkdir()
    with pytest.raises(ValueError, match="already exists"):
        check_companions(tmp_path / "table.csv", [tmp_path / "table.json"], never_ours, overwrite=True)


def test_an_input_or_the_output_itself_is_never_replaced(tmp_path):
    scene = tmp_path / "scene.xml"
    scene.write_text("<scene/>")
    output = tmp_path / "out.csv"
    with pytest.raises(ValueError, match=r"its companion file .*scene.xml would replace an input of this run"):
        check_companions(output, [scene], lambda path: True, overwrite=True, inputs=[scene, {"type": "dict"}])
    with pytest.raises(ValueError, match="would replace the output itself; choose another output name"):
        check_companions(output, [tmp_path / "." / "out.csv"], lambda path: True, overwrite=True)


def test_derived_seeds_are_32_bit_stable_and_distinct():
    import hashlib

    seed = derived_seed(7, "phi=0")
    assert seed == derived_seed(7, "phi=0") and 0 <= seed < 2**32
    assert seed == int.from_bytes(hashlib.blake2b(b"7:phi=0", digest_size=4).digest(), "little")
    seeds = {derived_seed(s, f"group {g}") for s in range(20) for g in range(50)}
    assert len(seeds) == 1000  # no collision among a thousand groups (a birthday bound of ~1e-4)

"""
Tests of :mod:`virtspec_mi.applications.klems.command`: ``virtspec klems`` and its alias ``virtspec gonio --klems``.

The alias writes the same matrices as the command (the same counts, bit for bit); it takes of
``gonio``'s flags only those it declares, refusing any other in one message; a basis that is
not Klems's is refused by name.

References
----------
Klems, J.H. (1994). ASHRAE Transactions 100(1), 1065–1072.
"""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.applications.klems.command import GONIO_KLEMS, KLEMS, KlemsCommandFlags, KlemsFlags
from virtspec_mi.applications.klems.matrices import read_klems_sidecar, sidecar_path
from virtspec_mi.cli import main


def test_the_alias_writes_the_commands_matrices(mi, tmp_path, capsys):
    common = ["--rays", "2000", "--isotropic", "--quiet", "--seed", "3"]
    assert main(["klems", "diamond_collimated", "--out", str(tmp_path / "a.xml"), "--basis", "quarter", *common]) == 0
    assert main(["gonio", "diamond_collimated", "--klems", str(tmp_path / "b.xml"), "--klems-basis", "quarter",
                 *common]) == 0
    capsys.readouterr()
    a = read_klems_sidecar(sidecar_path(tmp_path / "a.xml"))
    b = read_klems_sidecar(sidecar_path(tmp_path / "b.xml"))
    assert np.asarray(a.counts).size > 0
    np.testing.assert_array_equal(np.asarray(a.counts), np.asarray(b.counts))


def test_the_alias_refuses_gonios_other_flags(mi, tmp_path, capsys):
    assert main(["gonio", "diamond_collimated", "--klems", str(tmp_path / "c.xml"), "--theta-o-bins", "9",
                 "--quiet"]) == 1
    error = capsys.readouterr().err
    assert "--theta-o-bins" in error and "--klems" in error
    assert not (tmp_path / "c.xml").exists()
    assert set(GONIO_KLEMS.takes) == {"wavelengths", "mu", "delta", "rays", "seed", "quiet"}
    assert GONIO_KLEMS.command == "gonio" and GONIO_KLEMS.flags is KlemsFlags


def test_the_flags_and_their_refusals():
    flags = KlemsCommandFlags()
    assert (flags.basis, flags.epsilon, flags.delta, flags.rays, flags.isotropic) == ("full", 0.01, 0.01, None, False)
    check = KlemsCommandFlags.__dataclass_fields__["basis"].metadata["check"]
    assert check("half") == "half"
    with pytest.raises(ValueError, match=r"basis must be one of full, half, quarter \(got 'eighth'\)"):
        check("eighth")
    assert KLEMS.name == "klems" and KLEMS.flags is KlemsCommandFlags

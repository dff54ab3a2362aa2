"""The C/C++ header of an albedo table compiles with the system compiler and holds the table's numbers."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

from virtspec_mi.applications.tables.albedo import albedo_table
from virtspec_mi.exchange.header import read_table_values, write_header

PROGRAM = """
#include <stdio.h>
#include "table.h"
int main(void) {
    int i;
    printf("%.17g %.17g %llu\\n", TABLE_GGX_EPSILON, TABLE_GGX_DELTA, TABLE_GGX_RAYS);
    for (i = 0; i < TABLE_GGX_E_SIZE; i++) printf("%.9g\\n", (double)table_ggx_E[i]);
    for (i = 0; i < TABLE_GGX_EAVG_SIZE; i++) printf("%.9g\\n", (double)table_ggx_Eavg[i]);
    printf("%.17g\\n", TABLE_GGX_E_EPSILON);
    return 0;
}
"""


@pytest.fixture(scope="module")
def table(mi):
    return albedo_table("conductor", engine=None, mu=[1.0, 0.6, 0.2], alpha=[0.2, 0.9], epsilon=0.02, seed=2,
                        progress=False)


@pytest.mark.parametrize("compiler, flags, source", [("gcc", ["-std=c99", "-Wall", "-Werror", "-pedantic"], "main.c"),
                                                     ("g++", ["-std=c++11", "-Wall", "-Werror"], "main.cpp")])
def test_header_compiles_and_holds_the_table(table, tmp_path, compiler, flags, source):
    if shutil.which(compiler) is None:
        pytest.skip(f"the system compiler {compiler} is not installed on this machine")
    (tmp_path / "table.h").write_text(write_header(table))
    (tmp_path / source).write_text(PROGRAM)
    subprocess.run([compiler, *flags, source, "-o", "check"], cwd=tmp_path, check=True, capture_output=True)
    lines = subprocess.run([str(tmp_path / "check")], check=True, capture_output=True, text=True).stdout.split()
    epsilon, delta, rays = float(lines[0]), float(lines[1]), int(lines[2])
    assert (epsilon, delta, rays) == (table.epsilon, table.delta, table.rays)
    values = np.array([float(v) for v in lines[3:3 + 6]], dtype=np.float32)  # %.9g: a float32 reads back exactly
    assert np.array_equal(values, table.layout().ravel().astype(np.float32))
    avg = np.array([float(v) for v in lines[9:11]], dtype=np.float32)
    assert np.array_equal(avg, table.E_avg.astype(np.float32))
    assert float(lines[11]) == pytest.approx(np.nanmax(table.certified_epsilon()))


def test_cycles_layout_names_and_order(table):
    text = write_header(table)
    assert "static const float table_ggx_E[6]" in text and "static const float table_ggx_Eavg[2]" in text
    assert "memory order mu alpha" in text and "Mitsuba 3.9.1" in text
    # the values read back in the file's order are the table in Cycles' order: [mu][alpha], alpha fastest
    assert np.allclose(read_table_values_from(text, "table_ggx_E"), table.E.ravel(), atol=1e-8)


def read_table_values_from(text: str, name: str) -> np.ndarray:
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "t.h"
        path.write_text(text)
        return read_table_values(path, array=name)


def test_reading_published_headers(tmp_path):
    path = tmp_path / "pub.h"
    path.write_text("/* a */ static const float table_a[3] = {\n  0.5f, 1e-3f,\n  // c\n  .25f\n};\n"
                    "static const float table_b[1] = { 1.0f };\n")
    assert read_table_values(path, array="table_a").tolist() == [0.5, 1e-3, 0.25]
    with pytest.raises(ValueError, match="table_c"):
        read_table_values(path, array="table_c")
    with pytest.raises(ValueError, match="3 values; this table has 2 cells"):
        read_table_values(path, array="table_a", expected=2)


@pytest.mark.parametrize("compiler, flags, source", [("gcc", ["-std=c99", "-Wall", "-Werror", "-pedantic"], "main.c"),
                                                     ("g++", ["-std=c++11", "-Wall", "-Werror"], "main.cpp")])
def test_two_tables_headers_compile_in_one_translation_unit(table, tmp_path, compiler, flags, source):
    """Each header's macros carry its table's prefix (TABLE_GGX_…, TABLE_BECKMANN_…): none redefined (issue 33)."""

    if shutil.which(compiler) is None:
        pytest.skip(f"the system compiler {compiler} is not installed on this machine")
    other = albedo_table("conductor", distribution="beckmann", engine=None, mu=[1.0, 0.5], alpha=[0.3], epsilon=0.05,
                         seed=3, progress=False)
    (tmp_path / "ggx.h").write_text(write_header(table))
    (tmp_path / "beckmann.h").write_text(write_header(other))
    (tmp_path / source).write_text('#include <stdio.h>\n#include "ggx.h"\n#include "beckmann.h"\n#include "ggx.h"\n'
                                   'int main(void) { printf("%.17g %.17g\\n", TABLE_GGX_EPSILON, '
                                   "TABLE_BECKMANN_EPSILON); return (int)(table_ggx_E[0] + table_beckmann_E[0]) - 2; }\n")
    subprocess.run([compiler, *flags, source, "-o", "check"], cwd=tmp_path, check=True, capture_output=True)
    printed = subprocess.run([str(tmp_path / "check")], capture_output=True, text=True).stdout.split()
    assert [float(v) for v in printed] == [table.epsilon, other.epsilon]


def test_a_published_array_that_is_not_numbers_is_named():
    from virtspec_mi.exchange.header import read_table_values

    with pytest.raises(ValueError, match=r"published must be an array of numbers .* \(got a list holding 'a'\)"):
        read_table_values(["a"] * 6)


@pytest.mark.parametrize("text, message", [
    ("mu,alpha0.1,alpha0.5\n0.5,0.9,0.8\n", r"line 1: 'mu' is not a number \(a header row\?"),
    ("0,9;0,8\n0,7;0,6\n", r"line 1: '0,9' is written with a decimal comma"),
])
def test_a_published_text_table_with_a_header_or_decimal_commas_is_refused(tmp_path, text, message):
    from virtspec_mi.exchange.header import read_table_values

    (tmp_path / "pub.csv").write_text(text)
    with pytest.raises(ValueError, match=message):
        read_table_values(tmp_path / "pub.csv")
    (tmp_path / "ok.csv").write_text("# E over (mu, alpha)\n0.9, 0.8\n0.7 0.6\n")
    assert read_table_values(tmp_path / "ok.csv").tolist() == [0.9, 0.8, 0.7, 0.6]

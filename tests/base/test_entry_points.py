"""The one reader of a registry's entry-point group: virtspec_mi.base.entry_points.discovered."""

from __future__ import annotations

import warnings
from importlib.metadata import EntryPoint

import virtspec_mi.base.entry_points as rows
from virtspec_mi.applications import APPLICATIONS, ENTRY_POINTS
from virtspec_mi.applications.base import Application


class Outside(Application):
    name = "outside"
    summary = "an application of an outside package"


def test_an_outside_application_is_a_row_and_a_broken_one_is_left_out_with_a_warning(monkeypatch):
    points = [EntryPoint("outside", f"{__name__}:Outside", ENTRY_POINTS),
              EntryPoint("broken", "no_such_module:Nothing", ENTRY_POINTS),
              EntryPoint("targets", "virtspec_mi.applications.targets:TargetsApplication", ENTRY_POINTS),
              EntryPoint("plain", "virtspec_mi.settings:Settings", ENTRY_POINTS)]
    monkeypatch.setattr(rows, "entry_points", lambda group: points if group == ENTRY_POINTS else [])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        found = rows.discovered(ENTRY_POINTS, tuple(APPLICATIONS.values()), Application)
    assert list(found) == [*APPLICATIONS, "outside"] and found["outside"] is Outside
    messages = " | ".join(str(w.message) for w in caught)
    assert "'broken' (no_such_module:Nothing) could not be loaded" in messages
    assert "takes the name 'targets', already taken" in messages
    assert "'plain' (virtspec_mi.settings:Settings) is not a virtspec_mi Application class" in messages

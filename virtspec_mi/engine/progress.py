"""
Progress of a long run: one tqdm bar on stderr, only when it helps
==================================================================

``progress=True``: always a bar; ``False``: never; ``None`` (default): only when
stderr is a terminal and the run is expected to last more than about 2 s (the
estimate comes from the work done so far, in wall-clock time). A note about the run
(e.g. that it resumed from a checkpoint) goes to stderr too, unless ``progress=False``.

One bar per run, however deep the run's calls nest: a :class:`Progress` made while
another is open (in the same thread) draws nothing of its own and moves the enclosing
one instead — its share of the step the enclosing bar said was under way
(:meth:`Progress.expect`). So an albedo table's bar over its cells moves with every
kernel chunk of every group's sweep, and a sweep's bar over its readings moves with
every chunk of a batch, not once at the batch's end. The outermost bar alone decides
(its ``progress``) whether anything is drawn.
"""

from __future__ import annotations

import sys
import threading
import time
import weakref

__all__ = ["Progress", "expect", "finished", "write"]

_PROGRESS_AFTER_S = 2.0  # show a progress bar only when the run is expected to last longer
_FORMAT = "{desc}: {percentage:3.0f}%|{bar}| {n:.0f}/{total_fmt} {unit}s [{elapsed}<{remaining}]"
_OPEN_ENDED = "{desc}: {n_fmt} {unit}s [{elapsed}, {rate_fmt}]"  # a run whose length is not known in advance
_OPEN = threading.local()  # the bars open in this thread, outermost first


def _stack() -> list["Progress"]:
    """The bars open in this thread, outermost first (a bar dropped unclosed, e.g. by an error, is gone with it)."""

    refs = _OPEN.__dict__.setdefault("bars", [])
    refs[:] = [ref for ref in refs if ref() is not None]
    return [ref() for ref in refs]


def _push(bar: "Progress") -> None:
    _stack()
    _OPEN.bars.append(weakref.ref(bar))


def _pop(bar: "Progress") -> None:
    """Close ``bar`` on the stack, and any bar left open inside it."""

    bars = _stack()
    if bar in bars:
        del _OPEN.bars[bars.index(bar):]


def expect(units: float) -> None:
    """Tell the innermost open bar, if any, that the work now starting is worth ``units`` of it."""

    bars = _stack()
    if bars:
        bars[-1].expect(units)


def finished(units: float) -> None:
    """The work :func:`expect` announced is done: ``units`` more on the innermost open bar, if any."""

    bars = _stack()
    if bars:
        bars[-1].update(units)


def write(line: str) -> None:
    """One line on stderr, above the run's bar when one is drawn (never torn through it)."""

    bars = _stack()
    if bars and bars[0].bar is not None:
        bars[0].bar.write(line, file=sys.stderr)
    else:
        print(line, file=sys.stderr, flush=True)


class Progress:
    """
    A tqdm bar on stderr, shown per the ``progress`` rule (see the module docstring), over
    ``total`` units (``unit``, e.g. readings; ``None``: not known in advance, the units
    done and their rate are shown, once the run has lasted ~2 s when ``progress`` is
    ``None``). Made while another bar is open, it moves that bar by ``share`` of the step
    under way there (a fraction: the part of that step this work is) instead of drawing.
    """

    def __init__(self, progress: bool | None, total: float | None, desc: str = "readings", *, unit: str = "reading",
                 share: float = 1.0) -> None:
        bars = _stack()
        self.parent = bars[-1] if bars else None
        self.worth = None if self.parent is None or self.parent.step is None else share * self.parent.step
        self.mode, self.total, self.bar, self.done, self.desc, self.unit = progress, total, None, 0, desc, unit
        self.position = 0.0  # what the bar shows: the finished units and the nested bars' share of the step
        self.step: float | None = None  # units of the work under way (nested bars move within it)
        self._pending = 0.0
        self.elapsed = 0.0
        self._started = self._last = time.perf_counter()
        _push(self)
        if progress and self.parent is None:
            self._open()

    def _open(self) -> None:
        from tqdm import tqdm

        self.bar = tqdm(total=self.total, initial=self.position or 0, unit=self.unit, file=sys.stderr, leave=False,
                        desc=self.desc, bar_format=_FORMAT if self.total else _OPEN_ENDED,
                        unit_scale=not self.total)

    def expect(self, units: float) -> None:
        """The work starting now is worth ``units`` (nested bars move this one within it)."""

        self.step, self._pending = float(units), 0.0

    def update(self, count: float, seconds: float = 0.0) -> None:
        """``count`` more units finished (``seconds``: their time, kept for the caller's use)."""

        self.done += count
        self.elapsed += seconds
        self._pending = 0.0
        if self.total and self.done > self.total:  # more work than foreseen (a fit's extra readings): a longer bar
            self.total = self.done
            if self.bar is not None:
                self.bar.total = self.total
        self._show(self.done)

    def reach(self, done: float) -> None:
        """Move to ``done`` units in all (cumulative), timed since the last report."""

        now = time.perf_counter()
        if done > self.done:
            self.update(done - self.done, now - self._last)
        self._last = now

    def _advance(self, amount: float) -> None:
        """A nested bar moved: ``amount`` units of the step under way (never past it)."""

        self._pending += amount
        if self.step is not None:
            self._pending = min(self._pending, self.step)
        self._show(self.done + self._pending)

    def _show(self, target: float) -> None:
        target = min(float(target), float(self.total)) if self.total else float(target)
        delta = target - self.position
        if delta <= 0:
            return
        self.position = target
        if self.parent is not None:
            if self.worth and self.total:
                self.parent._advance(delta / self.total * self.worth)
            return
        if self.bar is None and self.mode is None and (not self.total or self.position < self.total) \
                and sys.stderr.isatty():
            spent = time.perf_counter() - self._started
            expected = spent / self.position * self.total if self.total else spent
            if expected > _PROGRESS_AFTER_S:
                self._open()
                return
        if self.bar is not None:
            self.bar.update(delta)

    def note(self, text: str) -> None:
        """One line on stderr about the run (unless the run's ``progress`` is ``False``: then nothing is shown)."""

        if self.parent is not None and self in _stack():
            self.parent.note(text)
            return
        if self.mode is False:
            return
        if self.bar is not None:
            self.bar.write(text, file=sys.stderr)
        else:
            print(text, file=sys.stderr, flush=True)

    def close(self) -> None:
        _pop(self)
        if self.bar is not None:
            self.bar.close()
            self.bar = None

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

"""
Progress of a long run: a tqdm bar on stderr, only when it helps
================================================================

``progress=True``: always a bar; ``False``: never; ``None`` (default): only when
stderr is a terminal and the run is expected to last more than about 2 s (the
estimate comes from the batches done so far). A note about the run (e.g. that it
resumed from a checkpoint) goes to stderr too, unless ``progress=False``.
"""

from __future__ import annotations

import sys
import time

__all__ = ["Progress"]

_PROGRESS_AFTER_S = 2.0  # show a progress bar only when the run is expected to last longer


class Progress:
    """A tqdm bar on stderr, shown per the ``progress`` rule (see the module docstring)."""

    def __init__(self, progress: bool | None, total: int, desc: str = "readings") -> None:
        self.mode, self.total, self.bar, self.done, self.desc = progress, total, None, 0, desc
        self.elapsed = 0.0
        self._last = time.perf_counter()
        if progress:
            self._open()

    def _open(self) -> None:
        from tqdm import tqdm

        self.bar = tqdm(total=self.total, initial=self.done, unit="reading", file=sys.stderr, leave=False,
                        desc=self.desc)

    def update(self, count: int, seconds: float) -> None:
        self.done += count
        self.elapsed += seconds
        if self.bar is None and self.mode is None and self.done < self.total and sys.stderr.isatty():
            expected = self.elapsed / self.done * self.total
            if expected > _PROGRESS_AFTER_S:
                self._open()
                return
        if self.bar is not None:
            self.bar.update(count)

    def reach(self, done: int) -> None:
        """Move to ``done`` readings in all (cumulative), timed since the last report."""

        now = time.perf_counter()
        if done > self.done:
            self.update(done - self.done, now - self._last)
        self._last = now

    def note(self, text: str) -> None:
        """One line on stderr about the run (unless ``progress=False``: then nothing is shown)."""

        if self.mode is False:
            return
        if self.bar is not None:
            self.bar.write(text, file=sys.stderr)
        else:
            print(text, file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


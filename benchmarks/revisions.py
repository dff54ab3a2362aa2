"""
Shared helpers of the benchmark scripts: the machine, and older git revisions
=============================================================================

- :func:`machine` / :func:`machine_lines` — the one machine description printed by
  every benchmark (CPU, cores, AVX2 / AVX-512 from ``/proc/cpuinfo``, Dr.Jit threads,
  libLLVM, versions, date). :func:`cpu` alone imports nothing heavy; :func:`runtime`
  imports Dr.Jit and Mitsuba, so call it after ``virtspec_mi.mitsuba()`` (which picks
  the libLLVM) — or in the process that ran the measurement.
- :func:`load_average` — the 1-minute load average (other work skews every figure).
- :func:`resolve`, :func:`show`, :func:`describe` — read-only git look-ups of the
  checkout (never the index or the branch).
- :class:`Worker` / :func:`serve` — a worker process of a benchmark script running another
  tree's code (``PYTHONPATH`` at the tree, checked with :func:`foreign_modules`), answering
  JSON requests line by line: the side-by-side runs of ``walk_queue.py`` and ``walk_ceiling.py``.
- :func:`find_bench` — the bench of a scene under the running tree's name for the function
  (``find_instrument`` before the subpackage layout).
- :func:`within_certificates` — whether two trees' readings agree within the sum of their
  certified tolerances (when a change alters the random stream, the counts differ).
- :func:`worktree` — a throwaway checkout of a revision in a temporary directory
  (``git worktree add --detach``, removed afterwards with ``git worktree remove
  --force``), importable with ``PYTHONPATH`` pointing at it (:func:`python_env`).
  The package maps ``virtspec_mi.plugins`` to the top-level ``plugins/`` directory
  (``[tool.setuptools.package-dir]``); a plain ``PYTHONPATH`` import needs the
  symlink ``virtspec_mi/plugins -> ../plugins``, which :func:`worktree` creates.
  Without it, the editable install's finder would quietly supply the *current*
  tree's plugins: check with :func:`foreign_modules`.

Used by ``throughput.py`` (``--against``), ``abm_spectrum.py`` (``--against``),
``walk_queue.py``, ``walk_ceiling.py`` and ``sweeps.py``.
"""

from __future__ import annotations

import contextlib
import datetime
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any, Callable, Iterator

ROOT = Path(__file__).resolve().parents[1]


# --- the machine ---------------------------------------------------------------------------


def cpu() -> dict:
    """CPU model, cores and the SIMD flags (AVX2, AVX-512) from ``/proc/cpuinfo``."""

    model, flags = platform.processor() or "unknown", set()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            if key.strip() == "model name":
                model = value.strip()
            elif key.strip() == "flags":
                flags = set(value.split())
    except OSError:
        pass
    return {
        "cpu": model,
        "cores": os.cpu_count(),
        "avx2": "avx2" in flags,
        "avx512": any(flag.startswith("avx512") for flag in flags),
    }


def runtime() -> dict:
    """Dr.Jit threads, libLLVM and the versions (imports Dr.Jit and Mitsuba)."""

    import drjit as dr
    import mitsuba
    import numpy as np

    return {
        "threads": dr.thread_count(),
        "llvm": ".".join(map(str, dr.detail.llvm_version())),
        "versions": f"drjit {dr.__version__}, mitsuba {mitsuba.__version__}, numpy {np.__version__}, "
                    f"python {platform.python_version()}",
    }


def now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")


def machine() -> dict:
    """CPU model, cores, SIMD flags, Dr.Jit threads, libLLVM, versions and the date (UTC)."""

    return {**cpu(), **runtime(), "date": now()}


def simd(info: dict) -> str:
    """The widest SIMD the CPU has: ``AVX-512``, ``AVX2`` or ``no AVX2``."""

    return "AVX-512" if info["avx512"] else "AVX2" if info["avx2"] else "no AVX2"


def load_average() -> float:
    """The 1-minute load average."""

    return os.getloadavg()[0]


def machine_lines(info: dict) -> list[str]:
    """The machine report: command, date, machine, versions and ``info['load']``."""

    return [
        f"command: {' '.join(sys.argv)}",
        f"date: {info['date']}",
        f"machine: {info['cpu']}, {info['cores']} cores, AVX2 {'yes' if info['avx2'] else 'no'}, "
        f"AVX-512 {'yes' if info['avx512'] else 'no'}; Dr.Jit threads {info['threads']}; "
        f"libLLVM {info['llvm']}",
        f"versions: {info['versions']}",
        f"load average (1 min): {info['load']}",
    ]


# --- git revisions (read-only for the checkout) --------------------------------------------


def git(*args: str) -> str:
    """Output of ``git -C ROOT args`` (raises with git's message on failure)."""

    done = subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"git {' '.join(args)} failed:\n{done.stderr.strip()}")
    return done.stdout


def resolve(revision: str) -> str:
    """The full commit hash of ``revision``."""

    try:
        return git("rev-parse", "--verify", "--quiet", f"{revision}^{{commit}}").strip()
    except RuntimeError:
        raise RuntimeError(f"{revision!r} is not a commit of {ROOT}") from None


def show(revision: str, path: str) -> str:
    """The text of ``path`` (relative to the repository root) at ``revision``."""

    return git("show", f"{revision}:{path}")


def describe_worktree() -> str:
    """``HEAD <short hash>``, plus ``+ uncommitted changes`` where tracked files differ from it."""

    head = git("rev-parse", "--short", "HEAD").strip()
    # --no-optional-locks: status must not refresh (write) the checkout's index.
    dirty = git("--no-optional-locks", "status", "--porcelain", "--untracked-files=no").strip()
    return f"HEAD {head}" + (" + uncommitted changes" if dirty else "")


@contextlib.contextmanager
def worktree(revision: str) -> Iterator[Path]:
    """
    A throwaway checkout of ``revision`` in a temporary directory, importable by
    ``PYTHONPATH`` (with the ``virtspec_mi/plugins -> ../plugins`` symlink); removed
    on exit with ``git worktree remove --force``.
    """

    parent = Path(tempfile.mkdtemp(prefix="virtspec-against-"))
    path = parent / "checkout"
    git("worktree", "add", "--detach", str(path), resolve(revision))
    try:
        link = path / "virtspec_mi" / "plugins"
        if (path / "plugins").is_dir() and not link.exists():
            link.symlink_to(Path("..") / "plugins", target_is_directory=True)
        yield path
    finally:
        try:
            git("worktree", "remove", "--force", str(path))
        finally:
            shutil.rmtree(parent, ignore_errors=True)


def python_env(path: Path) -> dict:
    """The environment with ``path`` first on ``PYTHONPATH`` (ahead of the editable install)."""

    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(path), env.get("PYTHONPATH")]))
    return env


def foreign_modules(root: Path, package: str = "virtspec_mi") -> list[str]:
    """
    The loaded modules of ``package`` whose file is not under ``root`` (run it in the
    process that imported them): empty when the process really runs ``root``'s code.
    """

    top = os.path.realpath(root) + os.sep
    found = []
    for name, module in list(sys.modules.items()):
        if name == package or name.startswith(package + "."):
            file = getattr(module, "__file__", None)
            if file is None or not os.path.realpath(file).startswith(top):
                found.append(f"{name} ({file})")
    return sorted(found)


# --- worker processes running another tree's code ------------------------------------------


def find_bench(scene: Any) -> Any:
    """
    The bench (specimen BSDF, geometry, frame) of a loaded ``scene``, by the running tree's
    name for it: ``virtspec_mi.runtime.scene.find_bench`` (``find_instrument`` before the subpackage
    layout of cff7fea), so a worker runs older trees too.
    """

    try:
        from virtspec_mi.runtime.scene import find_bench as find
    except ImportError:
        from virtspec_mi.runtime.scene import find_instrument as find
    return find(scene)


def within_certificates(old: dict, new: dict) -> tuple[bool, float, float]:
    """
    Whether two trees' readings agree within their certificates: ``old`` and ``new`` map a
    quantity's name to (values, μ) flattened over the readings; every |x_old − x_new| must
    be ≤ μ_old + μ_new (each certificate holds with probability ≥ 1 − δ), and a quantity
    with no certificate (μ = NaN: weight violations, capped walks or invalid directions)
    identical. Returns (whether all agree, the largest |Δx|, the smallest μ_old + μ_new).
    """

    import numpy as np

    inside, largest, smallest = True, 0.0, np.inf
    for name, (values, mu) in old.items():
        new_values, new_mu = new[name]
        allowed = np.asarray(mu) + np.asarray(new_mu)
        difference = np.abs(np.asarray(values) - np.asarray(new_values))
        certified = ~np.isnan(allowed)
        inside &= bool(np.all((difference <= allowed) | (~certified & (difference == 0.0))))
        largest = max(largest, float(difference.max()))
        smallest = min(smallest, float(allowed[certified].min()) if certified.any() else np.inf)
    return inside, largest, smallest if np.isfinite(smallest) else np.nan


def serve(root: Path, answer: Callable[[dict], dict], warm: Callable[[], dict] | None = None) -> None:
    """
    The worker side of :class:`Worker`: send stray output of Python or of native code to
    stderr (never into the replies), run ``warm()`` (optional: compile, warm up; its dict
    joins the hello), say hello (``virtspec_mi``'s file, how many of its modules are loaded and
    which of them come from outside ``root``), then ``answer`` each JSON request line on stdin
    with one JSON line.
    """

    replies = os.fdopen(os.dup(1), "w", buffering=1)
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    import virtspec_mi

    virtspec_mi.mitsuba()
    extra = warm() if warm is not None else {}
    modules = [name for name in sys.modules if name == "virtspec_mi" or name.startswith("virtspec_mi.")]
    hello = {"virtspec_mi": virtspec_mi.__file__, "modules": len(modules), "foreign": foreign_modules(root), **extra}
    print(json.dumps(hello), file=replies)
    for line in sys.stdin:
        print(json.dumps(answer(json.loads(line))), file=replies)


class Worker:
    """
    A worker process of ``script`` (``script --worker ROOT *arguments``, which calls
    :func:`serve`) importing ``virtspec_mi`` from ``root``. :meth:`start` waits for its hello
    (so several workers warm up at once) and refuses a worker that imported code from outside
    ``root``; :meth:`ask` sends one request and returns the reply.
    """

    def __init__(self, label: str, root: Path, script: Path, arguments: tuple[str, ...] = ()) -> None:
        self.label, self.root = label, root
        self.log = tempfile.TemporaryFile("w+")
        self.process = subprocess.Popen(
            [sys.executable, str(script), "--worker", str(root), *arguments], cwd=str(root), env=python_env(root),
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self.log, text=True, bufsize=1)
        self.hello: dict = {}

    def start(self) -> Worker:
        """Wait for the worker's hello and check that it runs ``root``'s virtspec_mi."""

        self.hello = self.receive()
        top = os.path.realpath(self.root) + os.sep
        if not os.path.realpath(self.hello["virtspec_mi"]).startswith(top) or self.hello["foreign"]:
            raise RuntimeError(f"{self.label}: the worker imported code from outside {self.root}: "
                               f"virtspec_mi from {self.hello['virtspec_mi']}; {self.hello['foreign']}")
        return self

    def receive(self) -> dict:
        line = self.process.stdout.readline()
        if not line:
            self.process.wait()
            self.log.seek(0)
            tail = "".join(self.log.readlines()[-30:])
            raise RuntimeError(f"{self.label}: the worker stopped (exit {self.process.returncode}):\n{tail}")
        return json.loads(line)

    def ask(self, **request: Any) -> dict:
        print(json.dumps(request), file=self.process.stdin, flush=True)
        return self.receive()

    def close(self) -> None:
        """End the worker (EOF on its stdin; killed if it has not exited within a minute)."""

        self.process.stdin.close()
        try:
            self.process.wait(timeout=60)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        self.process.stdout.close()
        self.log.close()

# virtspec-mi: `make demo` and `make test` set everything up on a fresh Debian 12 machine.
# Set-up is idempotent: a virtual environment in .venv, the project installed into it
# (editable, with the test extra), and a libLLVM that Dr.Jit 1.5 can use (libllvm19).

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
SUDO   := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
APT    ?= apt-get
PYTEST_ARGS ?=

.PHONY: setup venv llvm demo test test-slow docs lab bench notebooks clean

setup: $(STAMP) llvm

$(STAMP): pyproject.toml | venv
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test,docs]'
	@touch $(STAMP)

# A .venv whose pip is missing (left half-made by `python3 -m venv` on Debian/Ubuntu without the
# python3-venv package: "ensurepip is not available") is made again; python3-venv is installed with
# apt when missing, else named.
venv:
	@$(PY) -m pip --version >/dev/null 2>&1 || { \
	  if [ -e $(VENV) ]; then echo "setup: $(VENV) has no working pip (a half-made virtual environment): making it again"; \
	    rm -rf $(VENV); fi; \
	  $(PYTHON) -m venv $(VENV) >/dev/null 2>&1 || { \
	    rm -rf $(VENV); \
	    echo "setup: $(PYTHON) -m venv cannot install pip: the system package python3-venv is missing"; \
	    if command -v $(APT) >/dev/null 2>&1; then echo "setup: installing python3-venv with $(APT)"; \
	      $(SUDO) $(APT) update -qq && $(SUDO) DEBIAN_FRONTEND=noninteractive $(APT) install -y -qq python3-venv >/dev/null; \
	    fi; \
	    $(PYTHON) -m venv $(VENV) >/dev/null 2>&1 || { rm -rf $(VENV); \
	      echo "setup: install python3-venv (Debian/Ubuntu: sudo apt-get install python3-venv), then run make setup again" >&2; \
	      exit 1; }; }; }

# Dr.Jit aborts under libLLVM 14/15/16 (Debian 12's defaults): install 19 when no good one is found.
llvm: $(STAMP)
	@$(PY) -m virtspec_mi llvm find >/dev/null 2>&1 || { \
	  echo "setup: no libLLVM >= 17 found; installing Debian's libllvm19"; \
	  $(SUDO) apt-get update -qq && $(SUDO) DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19 >/dev/null; }
	@$(PY) -m virtspec_mi llvm check

demo: setup
	$(VENV)/bin/virtspec measure diamond_conical --theta-i 70

# The suite in two steps: every file but two on two pytest-xdist workers (whole files each),
# then, alone on the machine, the tests that time how fast a signal is answered (their bound is
# a latency, so they must not share the cores). Their signals land at seeded moments, so a
# failure is run once more: the same moment again, which a defect fails again and a stall of the
# machine does not. `make test` runs the tests not marked `slow` (under 10 minutes on a quiet
# 2-core machine); `make test-slow` the slow ones (large statistical checks, the manual's build
# and code, the notebooks, the wheel in a fresh environment); CI runs both.
SERIAL := tests/test_interrupts_anytime.py tests/base/test_interrupts.py
MARK   ?= not slow
SUITE   = $(PY) -m pytest -m "$(MARK)" -n 2 --dist loadfile $(addprefix --ignore=,$(SERIAL)) $(PYTEST_ARGS) \
	  && $(PY) -m pytest -m "$(MARK)" --reruns 1 $(SERIAL) $(PYTEST_ARGS)
test: setup
	$(SUITE)

test-slow: setup
	$(MAKE) --no-print-directory MARK=slow test


# The manual (Sphinx): docs/_build/html/index.html, warnings are errors (the tests build it too).
docs: setup
	$(PY) -m sphinx -E -W --keep-going -b html docs docs/_build/html

# Open the notebooks in JupyterLab (installs the notebook extra into .venv once).
lab: setup
	@$(PY) -c "import jupyterlab" 2>/dev/null || $(PY) -m pip install --quiet -e '.[test,docs,notebook]'
	$(VENV)/bin/jupyter lab notebooks

# Execute the notebooks (the paper reproduced) at full size and write their outputs back
# (several minutes); the test suite runs them at the reduced size.
notebooks: setup
	$(PY) notebooks/run.py --size full --inplace

bench: setup
	$(PY) benchmarks/throughput.py
	$(PY) benchmarks/sweeps.py
	$(PY) benchmarks/abm_spectrum.py
	$(PY) benchmarks/turbid_slab.py
	$(PY) benchmarks/speed_vs_error.py
	$(PY) benchmarks/tabulated.py
	$(PY) benchmarks/sphere.py
	$(PY) benchmarks/gonio.py
	$(PY) benchmarks/walk_ceiling.py

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache docs/_build docs/_generated

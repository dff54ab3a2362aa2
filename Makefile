# virtspec-mi: `make demo` and `make test` set everything up on a fresh Debian 12 machine.
# Set-up is idempotent: a virtual environment in .venv, the project installed into it
# (editable, with the test extra), and a libLLVM that Dr.Jit 1.5 can use (libllvm19).

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
SUDO   := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
PYTEST_ARGS ?=

.PHONY: setup llvm demo test test-fast docs lab bench notebooks clean

setup: $(STAMP) llvm

$(STAMP): pyproject.toml
	@[ -x $(PY) ] || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test,docs]'
	@touch $(STAMP)

# Dr.Jit aborts under libLLVM 14/15/16 (Debian 12's defaults): install 19 when no good one is found.
llvm: $(STAMP)
	@$(PY) -m virtspec_mi llvm find >/dev/null 2>&1 || { \
	  echo "setup: no libLLVM >= 17 found; installing Debian's libllvm19"; \
	  $(SUDO) apt-get update -qq && $(SUDO) DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19 >/dev/null; }
	@$(PY) -m virtspec_mi llvm check

demo: setup
	$(VENV)/bin/virtspec measure scenes/diamond_conical.xml --theta-i 70

# The whole suite, slow statistical tests included (plain `pytest` deselects them).
test: setup
	$(PY) -m pytest -m "slow or not slow" $(PYTEST_ARGS)

test-fast: setup
	$(PY) -m pytest $(PYTEST_ARGS)

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

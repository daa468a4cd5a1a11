# Two commands set everything up on a fresh machine with Python >= 3.11 and make:
#   make run    reduce the embedded campaign (raw/) into results/
#   make test   run the test suite (every kind: unit, slow, workflow, docs; tests/conftest.py)
#   make test-unit  the unit tests alone, in under a minute
#   make docs   write the docs/ pages from the results (docs/templates + results/)
#   make report results/report.html, the browsable report of the results of `make run`
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
CORES  ?= 2
STAMP  := $(VENV)/.installed

.PHONY: run test test-unit lint bench docs report venv clean dryrun unlock

# pip byte-compiles what it installs one file at a time (30 s of CPU, most of
# the install); compileall does it on every core. Compiled once here, as an
# environment with PYTHONDONTWRITEBYTECODE would compile at every import.
# The numba kernels are compiled into their on-disk cache here too: cold, each
# map job that starts compiles them itself (about 12 s of CPU, both first map
# jobs at once). Numba compiles on one core: beside compileall, not after it.
$(STAMP): requirements.lock pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet --no-compile -r requirements.lock
	$(BIN)/python -m pip install --quiet --no-deps --no-build-isolation -e .
	$(BIN)/python -m compileall -q -j 0 $(VENV)/lib & pid=$$!; \
	$(BIN)/python -c "from rocklab.kernels import compile_kernels; compile_kernels()" && wait $$pid
	touch $@

venv: $(STAMP)

run: $(STAMP)
	$(BIN)/snakemake --cores $(CORES) --printshellcmds --rerun-incomplete

# After a run killed outright, Snakemake's lock on the results stays behind.
unlock: $(STAMP)
	$(BIN)/snakemake --unlock

dryrun: $(STAMP)
	$(BIN)/snakemake --cores $(CORES) --dry-run

LINTED := src tests scripts bench

# snakefmt formats the rule files as ruff the Python; `snakemake --lint` runs
# in tests/test_workflow.py (clean but for its wish of a conda environment
# per rule: the environment is requirements.lock in the venv).
test: $(STAMP)
	$(BIN)/ruff check $(LINTED)
	$(BIN)/ruff format --check --quiet $(LINTED)
	$(BIN)/snakefmt --check Snakefile workflow
	$(BIN)/mypy
	$(BIN)/python -m pytest -n $(CORES) -q

test-unit: $(STAMP)
	$(BIN)/python -m pytest -m unit -n $(CORES) -q

# Every benchmark runs; one that misses its target fails `make bench` at the end.
bench: $(STAMP)
	rc=0; for b in bench/*.py; do $(BIN)/python $$b --out results/bench || rc=1; done; exit $$rc

# The pages of docs/ from the results of `make run` (rule docs, results/docs/),
# copied into docs/. mtime triggers: a change of the library's code does not
# recompute the campaign; --forcerun: a new results/bench/*.json is read.
RESULTS ?= results

docs: $(STAMP)
	$(BIN)/snakemake docs --cores $(CORES) --rerun-triggers=mtime --forcerun=docs --config results_dir=$(RESULTS)
	cp $(RESULTS)/docs/numbers.json $(RESULTS)/docs/*.md docs/

# Recomputes nothing: the report of what `make run` left in $(RESULTS).
report: $(STAMP)
	$(BIN)/snakemake --report $(RESULTS)/report.html --config results_dir=$(RESULTS)

clean:
	rm -rf results .snakemake

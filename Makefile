# Quick start: `make run` and `make test`. Both create .venv when it is missing.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: run test typecheck fuzz lint bench clean docs

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[dev,cluster,docs]"
	touch $(STAMP)

# The main experiment: the paper's Fig. 5 (four variants, 50 runs each), CDF plots and table.
run: $(STAMP)
	$(BIN)/kvi fig5 --out results/fig5 --rerun-other-code

# two pytest-xdist workers (the Dask tests share one worker and its cluster: loadgroup)
# (the numba kernels compile into their cache while mypy runs: about 30 CPU-s on a
# clean clone, on the core mypy leaves free; after mypy that core collects the tests
# once, so that pytest caches its rewritten test modules and each worker reads them:
# half its collection, about 3 CPU-s a worker. Pytest writes that cache only where
# Python may write bytecode: PYTHONDONTWRITEBYTECODE, set in some shells, is unset.)
PYTEST := PYTHONDONTWRITEBYTECODE= $(BIN)/python -m pytest
test: $(STAMP)
	$(BIN)/ruff check --no-cache .
	$(BIN)/ruff format --check --no-cache .
	$(BIN)/python tests/compile_kernels.py & warm=$$!; \
	  $(MAKE) --no-print-directory typecheck; status=$$?; \
	  $(PYTEST) --collect-only -q >/dev/null 2>&1; wait $$warm; exit $$status
	$(PYTEST) -n 2 --dist loadgroup

# mypy on the installed package. The folders install under one import name through
# setuptools package-dir, which mypy cannot follow (editable finder), so a tree of
# symlinks in .venv reproduces the installed layout; the config is [tool.mypy].
TYPECHECK_TREE := $(VENV)/typecheck
typecheck: $(STAMP)
	rm -rf $(TYPECHECK_TREE)
	mkdir -p $(TYPECHECK_TREE)/kalman_vs_infoset
	for d in kalman_vs_infoset/*; do \
	  case "$$d" in */__pycache__) continue;; esac; \
	  ln -s "$(CURDIR)/$$d" $(TYPECHECK_TREE)/kalman_vs_infoset/; \
	done
	for d in estim guidance experiments data; do \
	  ln -s "$(CURDIR)/$$d" $(TYPECHECK_TREE)/kalman_vs_infoset/$$d; \
	done
	cd $(TYPECHECK_TREE) && $(CURDIR)/$(BIN)/mypy --config-file $(CURDIR)/pyproject.toml \
	  --cache-dir $(CURDIR)/$(VENV)/.mypy_cache -p kalman_vs_infoset

# Random exploration of the property tests (the suite itself is derandomized):
# FUZZ_ROUNDS rounds from seed FUZZ_SEED on; a failure names the seed to replay.
FUZZ_ROUNDS ?= 10
FUZZ_SEED ?= $(shell date +%s)
fuzz: $(STAMP)
	@for i in $$(seq 0 $$(($(FUZZ_ROUNDS) - 1))); do \
	  s=$$(($(FUZZ_SEED) + i)); echo "fuzz round $$i: --hypothesis-seed=$$s"; \
	  HYPOTHESIS_PROFILE=fuzz $(BIN)/python -m pytest -q -p no:cacheprovider \
	    --hypothesis-seed=$$s $$(grep -l '@given' tests/*.py) || exit 1; \
	done

lint: $(STAMP)
	$(BIN)/ruff check . && $(BIN)/ruff format --check .

bench: $(STAMP)
	$(BIN)/kvi bench

clean:
	rm -rf $(VENV) results .pytest_cache .hypothesis

# The documentation site (Sphinx, pydata theme, executed gallery), warnings as errors;
# KVI_DOCS_QUICK=1 skips executing the gallery.
docs: $(STAMP)
	$(BIN)/python -m sphinx -W --keep-going -b html docs docs/_build/html

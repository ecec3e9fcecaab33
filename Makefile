# Two commands do everything on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp
BASE_STAMP := $(VENV)/.base-stamp

.PHONY: setup demo test test-fast lint bench docs clean mutation

# The package alone: what `make demo` needs.
$(BASE_STAMP): pyproject.toml
	@echo "make: installing gimwatch into $(VENV) (once; about 1-2 minutes)"
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e .
	touch $(BASE_STAMP)

# Everything the tests, notebooks and docs need.
$(STAMP): $(BASE_STAMP)
	@echo "make: installing the test, notebook and docs tools into $(VENV) (once)"
	$(PY) -m pip install --quiet -e '.[test,notebooks,docs,pandas]'
	touch $(STAMP)

setup: $(STAMP)

demo: $(BASE_STAMP)
	$(VENV)/bin/gimwatch demo -o demo-output

# The fast tier (under 3 minutes on 2 cores): every test not marked slow (tests/conftest.py
# lists the slow files).
test-fast: setup
	$(PY) -W error -c "import gimwatch"
	$(VENV)/bin/ruff check gimwatch tests
	$(VENV)/bin/ruff format --check gimwatch tests
	$(PY) -m mypy
	$(PY) -m pytest -n 2 -m "not slow" tests

# The fast tier first, then the slow one, the notebooks and the docs site.
test: test-fast
	$(PY) -m pytest -n 2 -m slow tests
	$(PY) -m pytest -n 2 --nbmake $(wildcard notebooks/*.ipynb)
	$(MAKE) docs

# The documentation site (docs/ -> site/), warnings as errors. Its python blocks, sh blocks and
# console transcripts are run by tests/test_docs.py; its API pages are read by
# tests/test_api_site.py.
docs: setup
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict

# Regenerates benchmarks/survey/ and the table of docs/findings/survey.md
.PHONY: survey
survey: setup
	$(VENV)/bin/gimwatch survey all --fixed --samples 200 --seed 0 --trajectory -o benchmarks/survey
	$(PY) benchmarks/survey/update_readme.py

# Full benchmark (about 30 min on 2 cores): regenerates every table under benchmarks/ in one
# run, the measured block of docs/findings/accuracy-costs.md and the table of
# docs/findings/cost.md. Each table's JSON records the code it measured
# (tests/test_bench_freshness.py fails once that code changes). Each figure has one home (the
# cost sections in benchmarks/cost/, the watch in a MuJoCo loop in benchmarks/watch_mujoco/
# and against the user's own lines in benchmarks/watch_overhead/, first contact in
# benchmarks/startup/), so no figure exists twice. Prose that quotes a figure is checked by
# tests/test_docs_numbers.py: update it after a run.
bench: setup
	$(PY) -m pip install --quiet -c constraints.txt -e '.[test,notebooks,docs,pandas]'
	$(VENV)/bin/gimwatch bench conditioning estimators accuracy dynamics integrators longchain \
		tighten -o benchmarks --page docs/findings/accuracy-costs.md
	$(VENV)/bin/gimwatch bench lean tracker denoc watch -o benchmarks/cost \
		--page docs/findings/accuracy-costs.md
	$(PY) -m gimwatch.bench.cost_page docs/findings/cost.md benchmarks/cost
	$(VENV)/bin/gimwatch bench watch_mujoco -o benchmarks/watch_mujoco
	$(VENV)/bin/gimwatch bench watch_overhead -o benchmarks/watch_overhead
	$(VENV)/bin/gimwatch bench explain -o benchmarks/explain
	$(VENV)/bin/gimwatch bench startup -o benchmarks/startup
	$(VENV)/bin/gimwatch bench digits -o benchmarks/digits
	$(PY) benchmarks/stability/stable_steps.py

# Planted bugs the tests must catch (tests/mutations.py): each applied in a temporary copy of
# the tree, its test subset run; prints caught/missed/stale per mutant. On demand, not in test.
mutation: setup
	$(PY) tests/mutations.py --jobs 2

lint: setup
	$(VENV)/bin/ruff check gimwatch tests
	$(VENV)/bin/ruff format --check gimwatch tests

clean:
	rm -rf $(VENV) demo-output site .pytest_cache

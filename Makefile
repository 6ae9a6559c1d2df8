# robotplan: `make demo` runs the main job on built-in defaults, `make test` the test suite.
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
DEMO   := demo

.PHONY: setup test test-slow lint demo bench clean

setup: $(STAMP)

$(STAMP): pyproject.toml setup.py robotplan/base/kernels.c
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --disable-pip-version-check -e '.[test]'
	touch $(STAMP)

test: setup
	$(PY) -m pytest

test-slow: setup
	$(PY) -m pytest -m slow

lint: setup
	$(VENV)/bin/ruff check robotplan tests tasks

demo: setup
	$(VENV)/bin/robotplan check tasks/*.yaml
	$(VENV)/bin/robotplan render tasks/*.yaml --out $(DEMO) --overwrite
	$(VENV)/bin/robotplan solve tasks/box_push.yaml --out $(DEMO)/box_push --overwrite
	@echo "SDF pictures in $(DEMO)/; the plan and its pybullet execution: $(DEMO)/box_push/playback.html"
	@echo "(robotplan view $(DEMO)/box_push serves it)"

bench: setup
	$(VENV)/bin/robotplan bench sdf --json

clean:
	rm -rf $(VENV) $(DEMO) .pytest_cache .ruff_cache

# The two commands of the README:  make demo  and  make test.
#   make demo  installs only what the demo needs (pedenv's core, no torch) and runs it.
#   make test  installs everything (every extra: ultralytics/torch to export the pose network
#              to ONNX offline, nuscenes-devkit, the viz writers) and prepares the ONNX models.
#   make test-fast  the tests without the slow end-to-end runs and the pose network.
#   make lint  ruff, mypy and the code-shape report (CI runs it after the tests).
#   make docs  the API reference from the docstrings into docs/api/ (CI builds it).

PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
CORE   := $(VENV)/.pedenv-core
FULL   := $(VENV)/.pedenv-full

.PHONY: setup setup-all demo test test-fast lint docs bench clean

$(CORE): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --disable-pip-version-check --no-compile -e .
	touch $(CORE)

$(FULL): $(CORE)
	$(BIN)/pip install --quiet --disable-pip-version-check -e ".[all]"
	YOLO_OFFLINE=1 $(BIN)/pedenv models prepare
	touch $(FULL)

setup: $(CORE)

setup-all: $(FULL)

demo: $(CORE)
	$(BIN)/pedenv demo --output output/demo

test: $(FULL)
	$(BIN)/python -m pytest

test-fast: $(FULL)
	$(BIN)/python -m pytest -q -m "not slow and not ultralytics and not onnx_model"

lint: $(FULL)
	$(BIN)/ruff check src tests benchmarks tools
	$(BIN)/mypy
	$(BIN)/python tools/code_shape.py --check

docs: $(FULL)
	$(BIN)/python tools/api_docs.py docs/api

bench: $(FULL)
	$(BIN)/pedenv bench

clean:
	rm -rf $(VENV) output docs/api

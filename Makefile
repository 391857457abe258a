# The two commands of the README:  make demo  and  make test.
# make test-fast: the tests without the slow end-to-end runs and the pose network (under a minute).
# make lint: ruff and mypy (CI runs it after the tests).
# Both create the virtual environment .venv with everything pedenv needs (the
# ultralytics/torch extra included, to export the pose network to ONNX offline).

PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.pedenv-setup

.PHONY: setup demo test test-fast lint bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e ".[all]"
	YOLO_OFFLINE=1 $(BIN)/pedenv models prepare
	touch $(STAMP)

setup: $(STAMP)

demo: setup
	$(BIN)/pedenv demo --output output/demo

test: setup
	$(BIN)/python -m pytest

test-fast: setup
	$(BIN)/python -m pytest -q -m "not slow and not ultralytics and not onnx_model"

lint: setup
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/mypy

bench: setup
	$(BIN)/pedenv bench

clean:
	rm -rf $(VENV) output

# assist3d: every target creates the virtual environment it needs by itself.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
OUT    ?= demo_out

.PHONY: demo test test-fast setup setup-full bench clean help

help:
	@echo "make demo   - set up and generate a small dataset from the built-in assets, then picture it"
	@echo "make test   - set up (with the training, LLM, sim and view extras) and run the test suite (both tiers)"
	@echo "make test-fast - the fast tier only (under a minute; what to run on every edit)"
	@echo "make bench  - time the generator at paper settings"

$(BIN)/activate:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip

$(VENV)/.core: pyproject.toml | $(BIN)/activate
	$(BIN)/pip install -q -e .
	touch $@

$(VENV)/.full: pyproject.toml | $(BIN)/activate
	$(BIN)/pip install -q "torch==2.13.0"
	$(BIN)/pip install -q -e ".[dev,train,llm,sim,ray,view]"
	touch $@ $(VENV)/.core

setup: $(VENV)/.core
setup-full: $(VENV)/.full

demo: $(VENV)/.core
	$(BIN)/assist3d generate --out $(OUT) --num-scenes 4 --seed 0
	$(BIN)/assist3d show $(OUT) --out $(OUT)_preview.png
	@echo "dataset in $(OUT)/, picture of the first scene beside it in $(OUT)_preview.png"

test: $(VENV)/.full
	$(BIN)/python -m pytest -q -m "not acceptance"

test-fast: $(VENV)/.full
	$(BIN)/python -m pytest -q

bench: $(VENV)/.core
	$(BIN)/assist3d bench

clean:
	rm -rf $(VENV) $(OUT) $(OUT)_preview.png .pytest_cache

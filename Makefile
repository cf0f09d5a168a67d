# wetcloth: the two commands of the README, and what they need.
#   make demo   build the FMU, co-simulate the default towel, write meshes, CSV and a plot to out/demo/
#   make test   run the whole test suite
# Both create the virtual environment .venv on first use.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test bench clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/wetcloth run --duration 90 --export out/demo/frames --csv out/demo/outputs.csv --plot out/demo/plot.png

test: $(STAMP)
	$(BIN)/python -m pytest -q

bench: $(STAMP)
	$(BIN)/python bench/step_speed.py

clean:
	rm -rf out build .pytest_cache

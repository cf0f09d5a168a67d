# wetcloth: the two commands of the README, and what they need.
#   make demo   build the FMU, co-simulate the default towel, write meshes, CSV and a plot to out/demo/
#   make test   run the whole test suite
#   make extension   the Blender extension dist/wetcloth-VERSION.zip (docs/blender.md section 8)
# Both create the virtual environment .venv on first use.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

# Blender for the exporter's import tests: bpy from PyPI in its own Python 3.11 venv (bpy pins
# numpy < 2, the project uses numpy 2). The wheels (bpy is 374 MB) are downloaded once into
# BLENDER_WHEELS and installed from there, so a rebuilt venv needs no download (pip's own HTTP
# cache does not reliably keep a file this large).  Override BLENDER_PYTHON if python3.11 is elsewhere.
BLENDER_PYTHON ?= $(shell command -v python3.11 || echo python3)
BLENDER_VENV := .venv-blender
BLENDER_STAMP := $(BLENDER_VENV)/.installed
BPY_VERSION := 5.0.1
BLENDER_WHEELS ?= $(HOME)/.cache/wetcloth/wheels

# What the installed package is built from: a change to the compiled core (C++) or to the presets
# (installed as wetcloth.presets) reinstalls; Python sources are used in place (editable install).
CORE_FILES := CMakeLists.txt $(shell find fmu_src/core -name '*.cpp' -o -name '*.hpp') $(wildcard models/*.toml models/studies/*.toml)

# The Blender tests once more on the newest bpy on PyPI (5.3.0, Python 3.13), by hand: make test-newest-blender
# (BLENDER_NEWEST_PYTHON=/path/to/python3.13 if python3.13 is not on the PATH).
BLENDER_NEWEST_PYTHON ?= python3.13
BLENDER_NEWEST_VENV := .venv-blender-newest
BPY_NEWEST := 5.3.0

.PHONY: demo test test-newest-blender bench extension clean

# The build's own requirements (pyproject.toml's build-system) go into the environment, and no isolated one is
# made: every build then shares build/ (the Blender extension's wheel relinks in seconds instead of compiling anew).
# The cmake package too, which fmpy (a test requirement) brings: installed after the first build, it would make
# scikit-build-core configure the next one with another CMake, which compiles everything again.
$(STAMP): pyproject.toml $(CORE_FILES)
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -c "import tomllib; print('\n'.join(tomllib.load(open('pyproject.toml', 'rb'))['build-system']['requires']))" \
		| xargs $(BIN)/python -m pip install --quiet cmake
	$(BIN)/python -m pip install --quiet --no-build-isolation -e '.[test]'
	touch $(STAMP)

$(BLENDER_STAMP):
	test -x $(BLENDER_VENV)/bin/python || $(BLENDER_PYTHON) -m venv $(BLENDER_VENV)
	$(BLENDER_VENV)/bin/python -c 'import sys; sys.exit(0 if sys.version_info[:2] == (3, 11) else "bpy $(BPY_VERSION) needs Python 3.11: rm -r $(BLENDER_VENV) and set BLENDER_PYTHON")'
	ls $(BLENDER_WHEELS)/bpy-$(BPY_VERSION)-*.whl >/dev/null 2>&1 || $(BLENDER_VENV)/bin/python -m pip download --quiet --dest $(BLENDER_WHEELS) bpy==$(BPY_VERSION)
	$(BLENDER_VENV)/bin/python -m pip install --quiet --no-index --find-links $(BLENDER_WHEELS) bpy==$(BPY_VERSION)
	touch $(BLENDER_STAMP)

demo: $(STAMP)
	$(BIN)/wetcloth demo

# Two workers (pytest-xdist): the machines CI runs on have two cores.
test: $(STAMP) $(BLENDER_STAMP)
	WETCLOTH_REQUIRE_BLENDER=1 $(BIN)/python -m pytest -q -n 2

$(BLENDER_NEWEST_VENV)/.installed:
	test -x $(BLENDER_NEWEST_VENV)/bin/python || $(BLENDER_NEWEST_PYTHON) -m venv $(BLENDER_NEWEST_VENV)
	ls $(BLENDER_WHEELS)/bpy-$(BPY_NEWEST)-*.whl >/dev/null 2>&1 || $(BLENDER_NEWEST_VENV)/bin/python -m pip download --quiet --no-deps --dest $(BLENDER_WHEELS) bpy==$(BPY_NEWEST)
	$(BLENDER_NEWEST_VENV)/bin/python -m pip install --quiet --find-links $(BLENDER_WHEELS) bpy==$(BPY_NEWEST)
	touch $@

test-newest-blender: $(STAMP) $(BLENDER_NEWEST_VENV)/.installed
	WETCLOTH_REQUIRE_BLENDER=1 WETCLOTH_BLENDER_PYTHON=$(CURDIR)/$(BLENDER_NEWEST_VENV)/bin/python $(BIN)/python -m pytest -q tests/test_blender.py tests/test_blender_extension.py tests/test_blender_roundtrip.py

extension: $(STAMP)
	$(BIN)/wetcloth blender-extension --out dist

# The quicker benchmarks; docs/benchmarks.md lists every one with its command.
bench: $(STAMP)
	$(BIN)/python bench/step_speed.py
	$(BIN)/python bench/skip_gains.py
	$(BIN)/python bench/export_speed.py
	$(BIN)/python bench/fmu_overhead.py

clean:
	rm -rf out build dist .pytest_cache

# Two commands for a fresh machine (Python 3.11 + a C compiler):
#   make demo   -- creates .venv, installs implgen, runs the main job
#   make test   -- same venv, the whole test suite
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.implgen-installed
SOURCES := pyproject.toml $(shell find generator templates runtime_c -type f \( -name '*.py' -o -name '*.j2' -o -name '*.c' -o -name '*.h' \
                       -o -name '*.html' -o -name '*.js' -o -name '*.css' \) 2>/dev/null)
C_FILES := $(wildcard runtime_c/*.c runtime_c/*.h tests/c/*.c tests/c/*.h bench/c/*.c)

.PHONY: demo test lint tools browser povray screenshot install regen gallery bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

# Dependencies once, then the package itself (non-editable, as a user gets it) whenever a source changes.
$(STAMP): $(BIN)/python $(SOURCES)
	$(BIN)/python -m pip install -q ".[test]"
	$(BIN)/python -m pip install -q --no-deps --force-reinstall .
	@touch $@

install: $(STAMP)

demo: install
	$(BIN)/implgen demo

test: install browser povray
	$(BIN)/python -m pytest -q tests

# Headless Chromium and its driver for the viewer's browser test (Debian packages; run as root, as CI does).
browser:
	@command -v chromium >/dev/null && command -v chromedriver >/dev/null || \
	  { apt-get update -qq && apt-get install -y -qq chromium chromium-driver >/dev/null; }

# POV-Ray for the exporter's tests that render with it (Debian package; run as root, as CI does).
povray:
	@command -v povray >/dev/null || { apt-get update -qq && apt-get install -y -qq povray >/dev/null; }

# The README's picture of `implgen view`, taken by the browser test.
screenshot: install browser
	IMPLGEN_SCREENSHOT=docs/gallery/view.png $(BIN)/python -m pytest -q tests/test_view_browser.py

# Style, checked not changed: ruff (lint + format) for Python, clang-format (.clang-format) for the C runtime.
lint: install
	$(BIN)/ruff check generator tests bench
	$(BIN)/ruff format --check generator tests bench
	@if [ -f .clang-format ]; then \
	  command -v clang-format >/dev/null || $(MAKE) --no-print-directory tools; \
	  clang-format --dry-run --Werror $(C_FILES); \
	fi

# Debian packages the checks need (run as root, as CI does).
tools:
	apt-get update -qq && apt-get install -y -qq clang-format >/dev/null

# Regenerate the checked-in generated/ folder from examples/shapes/.
regen: install
	$(BIN)/implgen examples/shapes/*.yaml --lang all -o generated

# Render every example scene into docs/gallery/ (images + times.md).
gallery: install
	$(BIN)/python bench/gallery.py

clean:
	rm -rf $(VENV) build *.egg-info

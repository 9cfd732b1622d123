# Two commands for a fresh machine (Python 3.11 + a C compiler):
#   make demo   -- creates .venv, installs implgen, runs the main job
#   make test   -- same venv, the whole test suite
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.implgen-installed
SOURCES := pyproject.toml $(wildcard examples/shapes/*.yaml) \
           $(shell find generator templates runtime_c runtime_glsl -type f \( -name '*.py' -o -name '*.j2' -o -name '*.c' -o -name '*.h' -o -name '*.glsl' \
                       -o -name '*.html' -o -name '*.js' -o -name '*.css' \) 2>/dev/null)
C_FILES := $(wildcard runtime_c/*.c runtime_c/*.h tests/c/*.c tests/c/*.h bench/c/*.c examples/embree/*.c)

.PHONY: demo test check lint tools browser povray glslang embree embree-example embree-picture screenshot install regen gallery bench clean dist blender blender-addon

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

# Dependencies once, then the package itself (non-editable, as a user gets it) whenever a source changes. setuptools
# builds in build/ and keeps what it finds there: a module moved or removed since would be installed still, so
# build/ goes first.
$(STAMP): $(BIN)/python $(SOURCES)
	rm -rf build
	$(BIN)/python -m pip install -q ".[test]"
	$(BIN)/python -m pip install -q --no-deps --force-reinstall .
	@touch $@

install: $(STAMP)

demo: install
	$(BIN)/implgen demo

test: install browser povray glslang embree blender
	$(BIN)/python -m pytest -q --durations=20 tests

# The quick tier a developer runs while working (under two minutes on 2 cores): a few fast test files from every
# room -- the house rules, the spec and its hostile inputs, each backend, the cache and ABI, the solvers and the
# C kernels by name, scenes, keyed frames, the viewer's API, share, export, mesh, the benchmarks' commands.
# `make test` stays the whole suite (docs/testing.md#two-tiers).
CHECK_TESTS := layout house_rules doc_links public_api codegen_hostile deep_nesting generator_bad_input \
  generator_textbook glsl_codegen abi cli_threads roots roots_auto descartes exactray raycast numerics_c \
  mesh_kernels_c scene_clip scene_camera two_sided renderjob render_loop scene_limits animation_keys fps_ranges \
  view_api view_gpu share_command povray_export mesh bench_gen bench_render output_lines
check: install
	$(BIN)/python -m pytest -q --durations=5 $(CHECK_TESTS:%=tests/test_%.py)

# $(call debian,PROGRAMS,PACKAGES,WHAT IS SKIPPED): when a program is missing, install the Debian packages as
# root (CI runs as root); as anyone else say in one line what is skipped and how to install it, and go on --
# unless IMPLGEN_REQUIRE_ALL is set (CI sets it): then stop. The tests skip or fail alike (tests/needs_program.py).
debian = $(call debian_if,command -v,$(1),$(2),$(3))
# $(call debian_if,CHECK,NAMES,PACKAGES,WHAT): the same with any check run on each name (`test -e` for a header).
debian_if = missing=; for p in $(2); do $(1) $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
  if [ -z "$$missing" ]; then :; \
  elif [ "$$(id -u)" = 0 ]; then apt-get update -qq && apt-get install -y -qq $(3) >/dev/null; \
  elif [ -n "$$IMPLGEN_REQUIRE_ALL" ]; then \
    echo "make:$$missing not installed and IMPLGEN_REQUIRE_ALL is set (as root: apt-get install $(3))" >&2; exit 1; \
  else echo "make:$$missing not installed: $(4) (as root: apt-get install $(3))"; fi

# Headless Chromium and its driver for the viewer's browser test.
browser:
	@$(call debian,chromium chromedriver,chromium chromium-driver,the browser tests will be skipped)

# Debian's Blender (3.4) for the add-on's headless test (docs/blender.md).
blender:
	@$(call debian,blender,blender,the Blender add-on test will be skipped)

# The Blender add-on as a zip to install (Edit > Preferences > Add-ons > Install; docs/blender.md).
blender-addon:
	$(PYTHON) blender/build_addon.py out/implgen_blender.zip

# POV-Ray for the exporter's tests that render with it.
povray:
	@$(call debian,povray,povray,the POV-Ray render tests will be skipped)

# Khronos' reference compiler, which validates every generated shader as GLSL ES 3.00 and as GLSL 4.50.
glslang:
	@$(call debian,glslangValidator,glslang-tools,the GLSL validation tests will be skipped)

# Embree 3 (its header and library) for the adapter's tests, examples/embree/ and bench/embree.py (docs/embree.md).
EMBREE_HEADER ?= /usr/include/embree3/rtcore.h
embree:
	@$(call debian_if,test -e,$(EMBREE_HEADER),libembree-dev,the Embree tests will be skipped)

# examples/embree/scene.c: generated shapes as Embree user geometry beside a triangle mesh, rendered to a PPM.
EMBREE_OUT ?= out/embree
EMBREE_SHAPES := torus_y heart chmutov8 sphere
EMBREE_SOURCES := examples/embree/scene.c runtime_c/embree_shape.c runtime_c/shape.c \
  $(filter-out runtime_c/roots_bench.c,$(wildcard runtime_c/roots*.c)) $(EMBREE_SHAPES:%=generated/%.c)
embree-example: embree
	@mkdir -p $(EMBREE_OUT)
	$${CC:-cc} -std=c99 -Wall -Wextra -Werror -pedantic -O2 -Iruntime_c -Igenerated -o $(EMBREE_OUT)/scene \
	  $(EMBREE_SOURCES) -lembree3 -lm
	$(EMBREE_OUT)/scene $(EMBREE_OUT)/scene.ppm

# The README's picture of it (docs/embree.md).
embree-picture: install embree-example
	$(BIN)/python -c "from PIL import Image; Image.open('$(EMBREE_OUT)/scene.ppm').save('docs/gallery/embree.png', optimize=True)"

# The README's picture of `implgen view`, taken by the browser test.
screenshot: install browser
	IMPLGEN_SCREENSHOT=docs/gallery/view.png $(BIN)/python -m pytest -q tests/test_view_browser.py
	IMPLGEN_VIEW_SHOTS=docs/gallery $(BIN)/python -m pytest -q tests/test_view_details.py -k three_window_sizes
	IMPLGEN_SHARE_SCREENSHOT=docs/gallery/share.png $(BIN)/python -m pytest -q tests/test_share_browser.py -k draws

# An sdist and a wheel (built from the sdist) in dist/, checked by twine: what `pip install` takes elsewhere.
dist: install
	rm -rf dist
	$(BIN)/python -m build --outdir dist .
	$(BIN)/twine check --strict dist/*

# Style, checked not changed: ruff (lint + format) for Python, clang-format (.clang-format) for the C runtime.
lint: install
	$(BIN)/ruff check generator tests bench blender
	$(BIN)/ruff format --check generator tests bench blender
	@if [ -f .clang-format ]; then \
	  $(MAKE) --no-print-directory tools || exit 1; \
	  if command -v clang-format >/dev/null; then clang-format --dry-run --Werror $(C_FILES); fi; \
	fi

# The programs the checks need.
tools:
	@$(call debian,clang-format,clang-format,the C style check will be skipped)

# Regenerate the checked-in generated/ folder from examples/shapes/.
regen: install
	$(BIN)/implgen examples/shapes/*.yaml --lang all -o generated

# Render every example scene into docs/gallery/ (images + times.md), and the famous surfaces' contact sheet.
gallery: install
	$(BIN)/python bench/gallery.py
	$(BIN)/python bench/surfaces.py

clean:
	rm -rf $(VENV) build dist *.egg-info

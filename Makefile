# gigascroll: `make demo` and `make test` set everything up on a fresh Debian 12 machine.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
PIP := $(VENV)/bin/pip
BUILD_DIR = $(shell ls -d build/cp3* 2>/dev/null | head -n 1)
APT_PACKAGES := build-essential cmake ninja-build pkg-config libembree-dev libzstd-dev \
  libxxhash-dev libgtest-dev libgmock-dev libbenchmark-dev libboost-dev \
  libconcurrentqueue-dev libreaderwriterqueue-dev libnanoflann-dev nlohmann-json3-dev \
  liblcms2-dev colord-data iipimage-server lighttpd ccache \
  xvfb xdotool libgl1-mesa-dri libglx-mesa0 libgs-common \
  libsquish-dev chromium fonts-droid-fallback
JOBS ?= $(shell nproc)
# Compiler cache: a second checkout (or a clean rebuild) compiles only what changed. CMake reads
# the launcher from the environment on first configure; BASEDIR makes paths checkout-relative.
export CMAKE_CXX_COMPILER_LAUNCHER := $(shell command -v ccache 2>/dev/null)
export CMAKE_C_COMPILER_LAUNCHER := $(CMAKE_CXX_COMPILER_LAUNCHER)
export CCACHE_BASEDIR := $(CURDIR)

.PHONY: all deps venv build demo test ctest pytest sanitize bench clean fuzz

all: build

# System packages: install only what is missing; print the command when not root.
deps:
	@missing=$$(for p in $(APT_PACKAGES); do dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    echo "installing Debian packages: $$missing"; \
	    apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q $$missing; \
	  else \
	    echo "missing Debian packages; run as root:"; \
	    echo "  apt-get update && apt-get install -y $$missing"; exit 1; \
	  fi; \
	fi

$(VENV)/.deps-stamp: pyproject.toml | deps
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PIP) install -q scikit-build-core nanobind ninja "cmake>=3.26"
	$(PIP) install -q numpy "OpenImageIO>=2.5" tqdm matplotlib pytest hypothesis pytest-timeout "pyvips[binary]" mitsuba trimesh
	$(PIP) install -q xxhash zstandard jsonschema pillow tifffile imagecodecs colour-science shapely
	$(PIP) install -q imageio-ffmpeg pyglet
	$(PIP) install -q "dask[distributed]"
	$(PIP) install -q flip-evaluator
	$(PIP) install -q playwright
	$(PIP) install -q aiohttp
	touch $@

venv: $(VENV)/.deps-stamp

# Editable install; the CMake build tree under build/ is kept, so a second run is incremental.
build: venv
	CMAKE_BUILD_PARALLEL_LEVEL=$(JOBS) $(PIP) install -q --no-build-isolation --no-deps -e . 

demo: build
	$(VENV)/bin/gigascroll demo --workdir build/demo

ctest: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

pytest: build
	$(PY) -m pytest -q

test: ctest pytest

# The long fuzz runs (tests marked `fuzz`: many more examples per family than `make test`).
fuzz: build
	GIGASCROLL_FUZZ=1 $(PY) -m pytest -q -m fuzz tests/python/test_fuzz_*.py --hypothesis-show-statistics

# C++ tests under sanitizers, each in its own build tree. Allocation failure must reach the
# code as std::bad_alloc (tested), not abort the run. Built for this CPU, as the module is, so
# that the vector paths (AVX2, AVX-512 where the CPU has them) run under the sanitizers too;
# the lane tests run the plain C++ width beside them (tests/cpp/display/test_lanes.cpp).
sanitize: deps
	cmake -S . -B build/asan -G Ninja -DGIGASCROLL_PYTHON=OFF -DGIGASCROLL_BENCH=OFF \
	  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGIGASCROLL_SANITIZE=address,undefined -DGIGASCROLL_NATIVE=ON
	cmake --build build/asan -j $(JOBS)
	cd build/asan && ASAN_OPTIONS=allocator_may_return_null=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 ctest --output-on-failure -j $(JOBS)
	cmake -S . -B build/tsan -G Ninja -DGIGASCROLL_PYTHON=OFF -DGIGASCROLL_BENCH=OFF \
	  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGIGASCROLL_SANITIZE=thread -DGIGASCROLL_NATIVE=ON
	cmake --build build/tsan -j $(JOBS)
	cd build/tsan && TSAN_OPTIONS=halt_on_error=1:allocator_may_return_null=1:suppressions=$(CURDIR)/tests/tsan.supp ctest --output-on-failure -j $(JOBS)

clean:
	rm -rf build

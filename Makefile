# animlod: the commands README shows. Each target installs what is missing first, so that on a
# fresh Debian 12 machine `make test` and `make demo` are one command each; a second run skips
# what is already there.
#
#   make setup     system packages, release OpenMesh, .venv with animlod installed
#   make test      ruff, C++ unit tests (ctest), the find_package(animlod) consumer, pytest
#   make demo      the main job on the embedded procedural character, into out/demo
#   make bench     benchmark tables (peers in the same run); heavy, not part of test
#   make bench-crowd  the native crowd benchmark: Table 2 and Fig. 1 of the motion LoD paper
#   make sanitize  C++ tests and pytest under ASan + UBSan
#   make fuzz      every fuzz harness of tests/fuzz for FUZZ_SECONDS (default 60) each

PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
OPENMESH := .deps/openmesh
OPENMESH_CONFIG := $(OPENMESH)/lib/cmake/OpenMesh/OpenMeshConfig.cmake
CPP_BUILD := build/cpp
CMAKE_GENERATOR := Ninja
JOBS ?= 2

.PHONY: setup system-packages python-package lint cpp-test consumer-test test demo bench bench-crowd crowd-binary sanitize fuzz fuzz-build clean

setup: python-package

system-packages:
	@scripts/install_system_packages.sh

$(OPENMESH_CONFIG): | system-packages
	scripts/build_release_openmesh.sh $(OPENMESH)

$(VENV)/bin/pip: | system-packages
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/pip install -q --upgrade pip

# An editable install: Python sources are used from the checkout, and the extension is
# rebuilt incrementally (build/python-*) whenever this target runs.
# Optional dependency groups of pyproject.toml; `make bench` adds the benchmark peers.
# wheel: without build isolation, setuptools before 70 needs it to build an sdist (meshoptimizer's
# Python package, which decodes EXT_meshopt_compression, comes as one).
EXTRAS := test,batch
python-package: $(OPENMESH_CONFIG) $(VENV)/bin/pip
	$(VENV)/bin/pip install -q scikit-build-core pybind11 pybind11-stubgen numpy wheel
	$(VENV)/bin/pip install -q --no-build-isolation -e ".[$(EXTRAS)]"

$(CPP_BUILD)/build.ninja: $(OPENMESH_CONFIG)
	@mkdir -p build
	cmake -S . -B $(CPP_BUILD) -G $(CMAKE_GENERATOR) -DCMAKE_BUILD_TYPE=Release \
	  -DCMAKE_INSTALL_PREFIX=$(CURDIR)/build/install > $(CPP_BUILD).configure.log

cpp-test: $(CPP_BUILD)/build.ninja
	cmake --build $(CPP_BUILD) --parallel $(JOBS)
	ctest --test-dir $(CPP_BUILD) --output-on-failure

# find_package(animlod) from a separate project after `cmake --install`.
consumer-test: cpp-test
	cmake --install $(CPP_BUILD) > /dev/null
	cmake -S tests/consumer -B build/consumer -G $(CMAKE_GENERATOR) \
	  -DCMAKE_PREFIX_PATH=$(CURDIR)/build/install > build/consumer.configure.log
	cmake --build build/consumer
	build/consumer/animlod_consumer

lint: python-package
	$(VENV)/bin/ruff check python tests bench
	$(VENV)/bin/ruff format --check python tests bench

# The crowd smoke test (tests/python/test_crowd.py) runs the binary under xvfb-run.
CROWD_BIN := $(CURDIR)/$(CPP_BUILD)/bench/crowd/animlod_crowd
test: python-package lint consumer-test
	ANIMLOD_GLTF_PROBE=$(CURDIR)/$(CPP_BUILD)/tests/cpp/animlod_gltf_probe ANIMLOD_CROWD_BIN=$(CROWD_BIN) \
	  $(PY) -m pytest -q tests/python

demo: python-package crowd-binary
	$(VENV)/bin/animlod demo -o out/demo
	ANIMLOD_CROWD_BIN=$(CROWD_BIN) $(VENV)/bin/animlod crowd out/demo/character_lod.glb --count 100 --frames 30 \
	  --modes all --level-colors --json out/demo/crowd.json --screenshot 15 out/demo/crowd.png

crowd-binary: $(CPP_BUILD)/build.ninja
	cmake --build $(CPP_BUILD) --target animlod_crowd --parallel $(JOBS)

# Heavy (tens of minutes on 2 cores): Table 2 on Nav1 and Nav2, 10,000 characters, Fig. 1.
bench-crowd: python-package crowd-binary
	ANIMLOD_CROWD_BIN=$(CROWD_BIN) $(PY) bench/crowd/run_bench.py

bench: EXTRAS := test,batch,bench
bench: python-package
	bench/openmesh_build/run.sh
	@for script in bench/bench_*.py; do echo "== $$script"; $(PY) $$script || exit 1; done

# The sanitizers: one ASan + UBSan build tree (build/sanitize) of the core, the doctest suite, the
# fuzz replays, the crowd (SANITIZE_CROWD=OFF leaves it and its loader's replay out) and the
# extension, so the core is compiled once; ctest, then pytest in the normal venv with the
# sanitized extension loaded in place of the release one (scripts/sanitize_site/sitecustomize.py,
# in every Python process the tests start too) and Debian's libasan preloaded into python.
# SANITIZE_BINDINGS=OFF compiles the thin pybind11 layer without sanitizers (most of the build's
# time). SANITIZE_PYTEST picks the tests (default: all of tests/python). -O1 -g1: line tables for the
# reports, and much less to compile than RelWithDebInfo's -O2 -g.
SANITIZE_FLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer
SANITIZE_ENV := ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
SANITIZE_CROWD ?= ON
SANITIZE_BINDINGS ?= ON
SANITIZE_PYTEST ?= tests/python

sanitize: python-package
	@mkdir -p build
	cmake -S . -B build/sanitize -G $(CMAKE_GENERATOR) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DCMAKE_CXX_FLAGS="$(SANITIZE_FLAGS)" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
	  -DANIMLOD_BUILD_PYTHON=ON -DANIMLOD_BUILD_CROWD=$(SANITIZE_CROWD) -DANIMLOD_INSTALL=OFF \
	  -DANIMLOD_SANITIZE_BINDINGS=$(SANITIZE_BINDINGS) -DANIMLOD_PYTHON_STUB=OFF \
	  -DPython_EXECUTABLE=$(CURDIR)/$(PY) -Dpybind11_DIR="$$($(PY) -m pybind11 --cmakedir)" > build/sanitize.configure.log
	cmake --build build/sanitize --parallel $(JOBS)
	$(SANITIZE_ENV) ctest --test-dir build/sanitize --output-on-failure
	$(SANITIZE_ENV) PYTHONPATH=$(CURDIR)/scripts/sanitize_site \
	  ANIMLOD_SANITIZED_CORE="$$(ls $(CURDIR)/build/sanitize/cpp/bindings/_core*.so)" \
	  LD_PRELOAD="$$(g++ -print-file-name=libasan.so) $$(g++ -print-file-name=libubsan.so)" \
	  $(PY) -m pytest -q -p no:cacheprovider $(SANITIZE_PYTEST)

# Fuzzing (tests/fuzz/README.md): clang's libFuzzer for the C++ harnesses, atheris for the
# readers. Its packages are installed here, not by `make test`, which replays saved crashes
# with g++ and pytest alone. New crashes land in tests/fuzz/crashes/<harness>/.
FUZZ_SECONDS ?= 60
FUZZ_CXX ?= clang++-14
FUZZ_PACKAGES := clang-14 libclang-rt-14-dev
FUZZ_FLAGS := -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer

fuzz-build: $(OPENMESH_CONFIG)
	@scripts/install_system_packages.sh $(FUZZ_PACKAGES)
	@mkdir -p build
	cmake -S . -B build/fuzz -G $(CMAKE_GENERATOR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=$(FUZZ_CXX) \
	  -DANIMLOD_BUILD_FUZZERS=ON -DANIMLOD_BUILD_TESTS=OFF -DANIMLOD_INSTALL=OFF \
	  -DCMAKE_CXX_FLAGS="$(FUZZ_FLAGS)" > build/fuzz.configure.log
	cmake --build build/fuzz --parallel $(JOBS)

fuzz: EXTRAS := test,batch,fuzz
fuzz: python-package fuzz-build
	FUZZ_SECONDS=$(FUZZ_SECONDS) $(PY) tests/fuzz/run.py $(FUZZ_ARGS)

clean:
	rm -rf build out

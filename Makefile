# mca: the two commands are `make demo` (the main job) and `make test` (every test).
# Both install their own dependencies first (`make deps`, idempotent).

BUILD     ?= build
ASAN_BUILD ?= build-asan
FUZZ_BUILD ?= build-fuzz
FUZZ_SECONDS ?= 300
FUZZ_TARGETS ?=
JOBS      ?= $(shell nproc)
PY        ?= python3
VENV      := $(CURDIR)/.venv
SUDO      := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
DEB_PKGS  := $(shell grep -v '^\#' tools/deps/debian-packages.txt)
STAMP_DEB := .deps-debian.stamp
STAMP_PY  := $(VENV)/.deps-python.stamp

.PHONY: all deps build test test-long asan-test fuzz demo bench sweep sweep-rt deb format format-check clean

all: build

deps: $(STAMP_DEB) $(STAMP_PY)

# Install only what is missing, so a second `make deps` is quick and offline.
$(STAMP_DEB): tools/deps/debian-packages.txt
	@missing=$$(for p in $(DEB_PKGS); do dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages:" $$missing; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; \
	fi
	@touch $@

$(STAMP_PY): tools/deps/requirements.txt $(STAMP_DEB)
	@[ -x $(VENV)/bin/python3 ] || $(PY) -m venv $(VENV)
	$(VENV)/bin/pip install -q --disable-pip-version-check -r tools/deps/requirements.txt
	@touch $@

$(BUILD)/CMakeCache.txt: $(STAMP_DEB)
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo

build: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

# every test but those labelled `long` (the full-length variants of the QEMU guest runs: `make test-long`)
test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) -LE long $(CTEST_ARGS)

# the tests labelled `long`: the QEMU guest end-to-end runs over the whole 50 s cup stacking task
# (canopen_mcad_e2e_long ~10 min, daemon_vcan_e2e_long ~4 min; `make test` runs their first 6 and 17 s)
test-long: build
	cd $(BUILD) && ctest --output-on-failure -L long $(CTEST_ARGS)

# ASan + UBSan build of everything, all tests except those marked `nosan`
# (the QEMU guest and wall-clock real-time runs, where the sanitizer runtime changes what is measured).
asan-test: deps
	cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMCA_SANITIZE=ON
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	cd $(ASAN_BUILD) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS) -LE nosan $(CTEST_ARGS)

# libFuzzer (clang) + ASan + UBSan: every decoder and parser (fuzz/), FUZZ_SECONDS each (default 300),
# one after the other; FUZZ_TARGETS="can_link cell" picks some. Figures: docs/fuzz.md.
fuzz: deps
	CC=clang CXX=clang++ cmake -S . -B $(FUZZ_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMCA_FUZZ=ON
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target fuzz_all
	bash fuzz/run.sh $(FUZZ_BUILD) $(FUZZ_SECONDS) $(FUZZ_TARGETS)

demo: build
	bash tools/demo.sh $(BUILD)

bench: build
	bash bench/run.sh $(BUILD)

# the random-task sweep alone (1000 two-arm + 200 three-arm + 400 pick-and-place tasks):
# out/bench/sweep.txt, sweep-{two,three,pnp}.json
sweep: build
	bash tools/mca-sweep/run_full.sh $(BUILD) $${MCA_BENCH_OUT:-$(CURDIR)/out/bench}

# sweep tasks through mcad at 1 kHz (sim arms, --no-dds, SCHED_FIFO on CPU 1) with cyclictest
# beside it, against the same tasks in virtual time (docs/sweep.md "Real time"); needs root; not in `make test`.
# SWEEP_RT_N tasks per kind (default 25: 50 pick-and-place + 50 crossing), out/sweep-rt/sweep-rt.txt
SWEEP_RT_N ?= 25
sweep-rt: build
	$(VENV)/bin/python3 tools/mca-sweep/sweep_rt.py --build $(BUILD) --n $(SWEEP_RT_N) \
	  --out $${MCA_SWEEP_RT_OUT:-$(CURDIR)/out/sweep-rt} $(SWEEP_RT_ARGS)

# the Debian package mca (docs/install.md): its own build with the prefix /usr in $(BUILD)/deb-build;
# the .deb lands in $(BUILD)/deb-build/deb/ (sudo apt install ./$(BUILD)/deb-build/deb/mca_*.deb)
deb: deps
	sh tools/deb/build_deb.sh . $(BUILD)/deb-build $(JOBS)

SOURCES_CMD = find core geom model firmware_iface dds sim_backend daemon tools bench tests fuzz \
	  \( -name '*.c' -o -name '*.h' -o -name '*.cpp' \) -print0

format:
	$(SOURCES_CMD) | xargs -0 -r clang-format -i

# CI: every C/C++ source as clang-format (.clang-format) writes it; `make format` fixes what this reports.
format-check: $(STAMP_DEB)
	$(SOURCES_CMD) | xargs -0 -r clang-format --dry-run -Werror

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) $(FUZZ_BUILD)

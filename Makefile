# The README's two commands: `make demo` (the main job) and `make test` (all tests).
# Both install missing Debian packages first through scripts/install-deps.sh, the only place
# that installs anything.
BUILD ?= build
OUT ?= out/demo
JOBS ?= $(shell nproc)

.PHONY: all deps configure build demo test bench sanitize fuzz format clean

all: build

deps:
	bash scripts/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release

build: configure
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	bash scripts/demo.sh $(BUILD)/bin/inhand $(OUT)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

bench: build
	bash scripts/bench.sh $(BUILD)

# ASan + UBSan over the units, parsers, fuzz targets, filter, tracker and importer
# (build-sanitize/); `bash scripts/sanitize.sh --all` runs every test under them.
sanitize: deps
	bash scripts/sanitize.sh

# The house style (.clang-format) applied to every C++ file; CI checks it.
format:
	bash scripts/format.sh

# The mutation fuzzer over every parser, longer than in make test (INHAND_FUZZ_RUNS per target).
fuzz: build
	INHAND_FUZZ_RUNS=$${INHAND_FUZZ_RUNS:-20000} $(BUILD)/bin/fuzz_tests

clean:
	rm -rf $(BUILD) build-sanitize out

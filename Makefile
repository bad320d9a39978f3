# Penumbra's front door. `make demo` and `make test` work on a fresh Debian 12 machine.
BUILD    ?= build
WERROR   ?= OFF
JOBS     ?= $(shell nproc)
PREFIX   ?= /usr/local
CMAKE_FLAGS = -DCMAKE_BUILD_TYPE=Release -DPENUMBRA_WERROR=$(WERROR) -DCMAKE_INSTALL_PREFIX=$(PREFIX)

.PHONY: all deps configure build demo test bench quality install format clean

all: build

deps:
	@bash scripts/install-deps.sh

configure: deps
	@cmake -S . -B $(BUILD) $(CMAKE_FLAGS) > $(BUILD).configure.log 2>&1 || (cat $(BUILD).configure.log; exit 1)

build: configure
	@cmake --build $(BUILD) -j $(JOBS)

demo:
	@BUILD=$(BUILD) JOBS=$(JOBS) WERROR=$(WERROR) bash scripts/demo.sh

test: build
	@cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

bench: build
	@$(BUILD)/bin/penumbra_bench --benchmark_counters_tabular=true

# The quality studies in docs/QUALITY.md (minutes: the path-traced references are cached).
quality: build
	@$(BUILD)/bin/penumbra bench-quality scenes/occluder.json -o docs/quality/occluder --doc docs/QUALITY.md --cache $(BUILD)/quality-cache
	@$(BUILD)/bin/penumbra bench-quality scenes/cornell.json --bounces 2 --reference-spp 2048 --max-spp 64 -o docs/quality/cornell --doc docs/QUALITY.md --cache $(BUILD)/quality-cache
	@$(BUILD)/bin/penumbra bench-quality scenes/pinhole.json --reference-spp 4096 --max-spp 64 -o docs/quality/pinhole --doc docs/QUALITY.md --cache $(BUILD)/quality-cache
	@$(BUILD)/bin/penumbra bench-quality scenes/fog.json --max-spp 64 -o docs/quality/fog --doc docs/QUALITY.md --cache $(BUILD)/quality-cache

install: build
	@cmake --install $(BUILD)

format:
	@clang-format -i $$(git ls-files '*.cpp' '*.hpp')

clean:
	@rm -rf $(BUILD) $(BUILD).configure.log out

# Penumbra's front door. `make demo` and `make test` work on a fresh Debian 12 machine.
BUILD    ?= build
WERROR   ?= OFF
JOBS     ?= $(shell nproc)
PREFIX   ?= /usr/local
# cmake's make runs as a top-level make, so it does not print "Entering directory" lines.
CMAKE_BUILD = env -u MAKELEVEL -u MAKEFLAGS -u MFLAGS cmake --build
CMAKE_FLAGS = -DCMAKE_BUILD_TYPE=Release -DPENUMBRA_WERROR=$(WERROR) -DCMAKE_INSTALL_PREFIX=$(PREFIX)
# The sanitizer build (docs/RELIABILITY.md): ASan + UBSan, no benchmarks (no test runs them).
ASAN_BUILD ?= build-asan
ASAN_FLAGS = -DCMAKE_BUILD_TYPE=Release -DPENUMBRA_WERROR=$(WERROR) -DPENUMBRA_SANITIZE=ON \
             -DPENUMBRA_BUILD_BENCH=OFF
FUZZ_SECONDS ?= 60

.PHONY: all deps configure build demo test bench quality quality-family install format clean \
        build-sanitize test-sanitize fuzz test-shared scene-images reference-error quality-family-speedup

all: build

deps:
	@bash scripts/install-deps.sh

configure: deps
	@cmake -S . -B $(BUILD) $(CMAKE_FLAGS) > $(BUILD).configure.log 2>&1 || (cat $(BUILD).configure.log; exit 1)

build: configure
	@$(CMAKE_BUILD) $(BUILD) -j $(JOBS)

demo:
	@BUILD=$(BUILD) JOBS=$(JOBS) WERROR=$(WERROR) bash scripts/demo.sh

test: build
	@bash scripts/ctest.sh $(BUILD) $(JOBS)

build-sanitize: deps
	@cmake -S . -B $(ASAN_BUILD) $(ASAN_FLAGS) > $(ASAN_BUILD).configure.log 2>&1 || (cat $(ASAN_BUILD).configure.log; exit 1)
	@$(CMAKE_BUILD) $(ASAN_BUILD) -j $(JOBS)

# Every test under ASan + UBSan but the studies named in tests/sanitize-skip.txt; ctest passes
# LSAN_OPTIONS (tests/lsan.supp) to each test. UBSan aborts on any report
# (-fno-sanitize-recover); these options add the stack.
SANITIZE_SKIP = $(shell sed -e 's/\#.*//' tests/sanitize-skip.txt | awk 'NF { print $$1 }' | paste -sd'|')
test-sanitize: build-sanitize
	@UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 bash scripts/ctest.sh $(ASAN_BUILD) $(JOBS) \
	  -E '^($(SANITIZE_SKIP))$$'

# Each libFuzzer target for FUZZ_SECONDS (scripts/fuzz.sh; clang, build dir build-fuzz).
fuzz: deps
	@JOBS=$(JOBS) WERROR=$(WERROR) bash scripts/fuzz.sh $(FUZZ_SECONDS)

bench: build
	@$(BUILD)/bin/penumbra_bench --benchmark_counters_tabular=true

# The quality studies in docs/QUALITY.md (minutes: the path-traced references are cached; the
# 3D closed forms, about 16 s on 2 cores, write docs/quality/3d/quality3d.md and spwi3d.md; the
# probe grid's, about 6 min, grid3d.md). The 3D scenes of the SPWI and probe grid study (a
# reference of 1024 spp each, 20-50 s; then 1-5 min of runs), and the Cornell box at 2 to 4
# bounces.
QUALITY_3D = cornell offscreen bunny_sky bunny_lights two_rooms four_cubes fog_shaft
quality: build
	@$(BUILD)/bin/penumbra bench-quality scenes/occluder.json -o docs/quality/occluder --doc docs/QUALITY.md --cache $(BUILD)/quality-cache
	@$(BUILD)/bin/penumbra bench-quality scenes/cornell.json --bounces 2 --reference-spp 2048 --max-spp 64 -o docs/quality/cornell --doc docs/QUALITY.md --cache $(BUILD)/quality-cache
	@$(BUILD)/bin/penumbra bench-quality scenes/pinhole.json --reference-spp 4096 --max-spp 64 -o docs/quality/pinhole --doc docs/QUALITY.md --cache $(BUILD)/quality-cache
	@$(BUILD)/bin/penumbra bench-quality scenes/fog.json --max-spp 64 -o docs/quality/fog --doc docs/QUALITY.md --cache $(BUILD)/quality-cache
	@$(BUILD)/bin/penumbra_quality3d docs/quality/3d > /dev/null
	@$(BUILD)/bin/penumbra_quality3d docs/quality/3d --grid-only > /dev/null
	@for s in $(QUALITY_3D); do \
	  $(BUILD)/bin/penumbra bench-quality scenes/3d/$$s.json -o docs/quality/3d/study/$$s --doc docs/QUALITY.md --cache $(BUILD)/quality-cache || exit 1; \
	done
	@for b in 2 3 4; do \
	  $(BUILD)/bin/penumbra bench-quality scenes/3d/cornell.json --bounces $$b -o docs/quality/3d/study/cornell-b$$b --doc docs/QUALITY.md --cache $(BUILD)/quality-cache || exit 1; \
	done
	@bash scripts/quality-family.sh $(BUILD) docs/quality/family 4 1024
	@bash scripts/family-speedup.sh $(BUILD) docs/quality/family

# The random scene family alone (docs/QUALITY.md, "The scene family": 12 scenes at 1 and 2
# bounces; the path-traced references, 1024 spp, cached in $(BUILD)/quality-cache/family).
quality-family: build
	@bash scripts/quality-family.sh $(BUILD) docs/quality/family 4 1024

# The family's equal-error speed-ups against the path tracer (bench-quality --quick on each scene
# at 1 and 2 bounces, docs/quality/family/speedup.md; minutes).
quality-family-speedup: quality-family
	@bash scripts/family-speedup.sh $(BUILD) docs/quality/family

# Every picture of scenes/README.md, from the command printed under it (minutes, mostly the 3D
# path-traced ones); prints each command's time.
scene-images: build
	@bash scripts/scene-images.sh $(BUILD)

# The own error of each path-traced 3D picture of scenes/README.md (its command at two seeds;
# the README quotes them; about 15 minutes on 2 cores).
reference-error: build
	@bash scripts/reference-error.sh $(BUILD)

# The library as shared libraries (-DBUILD_SHARED_LIBS=ON): built, installed into a scratch
# prefix and linked by examples/ through find_package(penumbra), which must then need no
# dependency but TBB at link time (tests/apps/install_test.sh).
SHARED_BUILD ?= build-shared
test-shared: deps
	@cmake -S . -B $(SHARED_BUILD) -DCMAKE_BUILD_TYPE=Release -DPENUMBRA_WERROR=$(WERROR) \
	  -DBUILD_SHARED_LIBS=ON -DPENUMBRA_BUILD_TESTS=OFF -DPENUMBRA_BUILD_BENCH=OFF \
	  > $(SHARED_BUILD).configure.log 2>&1 || (cat $(SHARED_BUILD).configure.log; exit 1)
	@$(CMAKE_BUILD) $(SHARED_BUILD) -j $(JOBS) --target penumbra_cli
	@SHARED=1 bash tests/apps/install_test.sh $(abspath $(SHARED_BUILD)) $(CURDIR) \
	  $(abspath $(SHARED_BUILD))/install_test

install: build
	@cmake --install $(BUILD)

format:
	@clang-format -i $$(git ls-files '*.cpp' '*.hpp')

clean:
	@rm -rf $(BUILD) $(BUILD).configure.log out $(ASAN_BUILD) $(ASAN_BUILD).configure.log \
	        build-fuzz build-fuzz.configure.log

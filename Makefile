# Weft: set-up, build, demo and tests, one command each (README, "Quick start").
#   make demo   install missing packages, build Release into build/, simulate the flag scene and
#               render it headless to PNGs (plus an MP4 when ffmpeg is installed)
#   make test   the same set-up and build, a short run of every fuzz target, then the whole test suite
# Other targets: build, asan, fuzz, format, tidy, clean. Variables can be overridden: make demo DEMO_FRAMES=60

BUILD_DIR   ?= build
JOBS        ?= $(shell nproc 2>/dev/null || echo 2)
CMAKE_FLAGS ?=

# The demo runs in about a minute on 2 cores. DEMO_SET holds `--set` overrides (key=value, no spaces),
# e.g. DEMO_SET='cloth.0.mesh.grid.cells=[64,64] solver.substeps=2'.
DEMO_SCENE  ?= flag
DEMO_FRAMES ?= 300
DEMO_SET    ?= cloth.flag.mesh.grid.cells=[90,54]
DEMO_OUT    ?= out/demo
DEMO_CAPTURE ?= egl
DEMO_SIZE   ?= 960x540

WEFT := $(BUILD_DIR)/bin/weft

.PHONY: all deps configure build demo test asan fuzz fuzz-build fuzz-smoke format tidy clean

all: build

deps:
	tools/deps.sh

configure: deps
	cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Release -DWEFT_WERROR=ON $(CMAKE_FLAGS)

build: configure
	cmake --build $(BUILD_DIR) -j$(JOBS)

demo: build
	rm -rf $(DEMO_OUT)
	$(WEFT) run $(DEMO_SCENE) --frames $(DEMO_FRAMES) $(foreach s,$(DEMO_SET),--set '$(s)') \
	    --capture $(DEMO_CAPTURE) --size $(DEMO_SIZE) --out $(DEMO_OUT) --stats $(DEMO_OUT)/stats.json
	@echo
	@echo "demo output: $(DEMO_OUT)/frame_*.png (one picture per frame, frame 0 = initial state)"
	@echo "             $(DEMO_OUT)/contact_sheet.png, $(DEMO_OUT)/capture.mp4 (with ffmpeg)"
	@echo "             $(DEMO_OUT)/stats.json (timings, CG iterations, memory, capture)"

test: build fuzz-smoke
	ctest --test-dir $(BUILD_DIR) --output-on-failure -j$(JOBS)

# libFuzzer targets (docs/fuzzing.md), from CMakePresets.json into build-fuzz/ with clang, ASan and
# UBSan: `make test` runs each briefly (FUZZ_SMOKE_RUNS executions after its seeds); `make fuzz` runs
# each FUZZ_RUNS times and prints the table of docs/fuzzing.md.
FUZZ_SMOKE_RUNS ?= 3000
FUZZ_RUNS       ?= 1000000
FUZZ_TARGETS     = fuzz_scene_loader fuzz_mesh_import fuzz_editor_script
fuzz-build: deps
	cmake --preset fuzz > /dev/null
	cmake --build --preset fuzz -j$(JOBS) --target $(FUZZ_TARGETS)

fuzz-smoke: fuzz-build
	fuzz/run_fuzzers.sh build-fuzz $(FUZZ_SMOKE_RUNS)

fuzz: fuzz-build
	fuzz/run_fuzzers.sh build-fuzz $(FUZZ_RUNS)

# Address + undefined-behaviour sanitizers (CPU only), from CMakePresets.json into build-asan/.
asan: deps
	cmake --preset asan-ubsan
	cmake --build --preset asan-ubsan -j$(JOBS)
	ctest --preset asan-ubsan -j$(JOBS)

format:
	@command -v clang-format >/dev/null || { echo "make format: clang-format not found (apt-get install clang-format)"; exit 1; }
	git ls-files --cached --others --exclude-standard -- '*.h' '*.hpp' '*.cpp' '*.cu' '*.cuh' | xargs -r clang-format -i

tidy: configure
	@command -v run-clang-tidy >/dev/null || { echo "make tidy: run-clang-tidy not found (apt-get install clang-tidy)"; exit 1; }
	run-clang-tidy -p $(BUILD_DIR) -quiet '/(runtime|assets|tools|cuda|render|editor)/'

clean:
	rm -rf $(BUILD_DIR) build-asan build-fuzz out

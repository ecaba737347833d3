# skelcd — the two Quick-start commands (`make demo`, `make test`) and a few more.
# Every target installs missing Debian packages first (scripts/install-deps.sh).

BUILD      ?= build
SAN_BUILD  ?= build-sanitize
JOBS       ?= $(shell nproc)
# CI sets CI=true: warnings become errors there.
WERROR     ?= $(if $(CI),ON,OFF)
CMAKE_ARGS ?=
# make fuzz (docs/fuzzing.md): seconds per harness, which harnesses, the clang build folder.
FUZZ_SECONDS ?= 600
FUZZERS      ?= scene ccd_queries frame_mesh trajectory srdf log_reader assimp_import
FUZZ_BUILD   ?= build-fuzz

.PHONY: all deps configure build demo test sanitize sanitize-ci format-check bench bench-real fuzz sweep clean

all: build

deps:
	@bash scripts/install-deps.sh

$(BUILD)/build.ninja: | deps
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release -DSKELCD_WERROR=$(WERROR) $(CMAKE_ARGS)

configure: $(BUILD)/build.ninja

build: deps configure
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	bash scripts/demo.sh $(BUILD)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) -LE bench

sanitize: deps
	cmake -S . -B $(SAN_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Debug -DSKELCD_SANITIZE=ON -DSKELCD_WERROR=$(WERROR) $(CMAKE_ARGS)
	cmake --build $(SAN_BUILD) -j $(JOBS)
	cd $(SAN_BUILD) && ctest --output-on-failure -j $(JOBS) -LE bench

# CI's sanitizer lane (.ci/run): ASan + UBSan over the tests of what reads files and guards
# processes — import (the forked child, memory limits), frame sequences and the order they are
# held in, the CCD kernels, the log (checksums, a full disk), bad input at the command line —
# within CI's time; and RobotExpressive's whole clip checked with `bvh`, `dynamic` and `auto`,
# serial and parallel (ParallelCheck.WholeClip…, 60-90 s here), which found a heap read before an
# array at its collapsed sides (stop 76).
SAN_CI_TARGETS ?= skelcd skelcd_ccd_tests skelcd_skinning_tests skelcd_tools_tests
SAN_CI_TESTS   ?= WholeSlots|Runner\.ARowIsTheCallbacks|ParallelRunner\.RowsTheCallbackTakes|ImportRobustness|ImportGuard|AssimpImport|FrameSequence|MeshOrder|Log\.|BadInputCli|CmdInspect|Vertex|Edge|TriangleTriangle|Expansion|CoplanarityScreen\.EachLaneIsTheKernelsScreenOnTheClothFunnel|RelativeBoxes\.(Keeps|Rejects|Without)|ParallelCheck\.WholeClipOfABundledCharacterLogsEqualSerialOnTwoThreads
sanitize-ci: deps
	cmake -S . -B $(SAN_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Debug -DSKELCD_SANITIZE=ON -DSKELCD_WERROR=$(WERROR) $(CMAKE_ARGS)
	cmake --build $(SAN_BUILD) -j $(JOBS) --target $(SAN_CI_TARGETS)
	cd $(SAN_BUILD) && ctest --output-on-failure -j $(JOBS) -LE bench -R '$(SAN_CI_TESTS)'

# Every C++ line changed since .ci/format-base must be as clang-format makes it.
format-check:
	bash scripts/check_format.sh

# scripts/sweep_models.py: `info` on every file of Debian's assimp test models (docs/bad-input.md).
sweep: build
	/usr/bin/python3 scripts/sweep_models.py $(BUILD)/tools/skelcd

bench: build
	bash scripts/bench.sh $(BUILD)

# scripts/bench_real.sh (docs/benchmarks.md "Real assets"): DCD against CGAL (libcgal-dev, for this
# benchmark only), CCD of every method, peak memory, on the bundled, Debian and cloth assets.
# BENCH_REAL_ARGS passes options to scripts/bench_real.py (e.g. --no-debian --cap 20).
BENCH_REAL_ARGS ?=
bench-real: build
	@bash scripts/install-deps.sh libcgal-dev
	cmake -S . -B $(BUILD)
	cmake --build $(BUILD) -j $(JOBS) --target dcd_vs_cgal
	bash scripts/bench_real.sh $(BUILD) $(BENCH_REAL_ARGS)

fuzz: deps
	@bash scripts/install-deps.sh clang-14 libclang-rt-14-dev
	CC=clang-14 CXX=clang++-14 cmake -S . -B $(FUZZ_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g" "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g" -DSKELCD_FUZZ=ON -DSKELCD_WERROR=OFF $(CMAKE_ARGS)
	nice -n 10 cmake --build $(FUZZ_BUILD) -j $(JOBS) --target $(addprefix fuzz_,$(FUZZERS))
	FUZZ_SECONDS=$(FUZZ_SECONDS) bash scripts/fuzz.sh $(FUZZ_BUILD) $(FUZZERS)

clean:
	rm -rf $(BUILD) $(SAN_BUILD)

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

.PHONY: all deps configure build demo test sanitize bench fuzz clean

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

bench: build
	bash scripts/bench.sh $(BUILD)

fuzz: deps
	@bash scripts/install-deps.sh clang-14 libclang-rt-14-dev
	CC=clang-14 CXX=clang++-14 cmake -S . -B $(FUZZ_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g" "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g" -DSKELCD_FUZZ=ON -DSKELCD_WERROR=OFF $(CMAKE_ARGS)
	nice -n 10 cmake --build $(FUZZ_BUILD) -j $(JOBS) --target $(addprefix fuzz_,$(FUZZERS))
	FUZZ_SECONDS=$(FUZZ_SECONDS) bash scripts/fuzz.sh $(FUZZ_BUILD) $(FUZZERS)

clean:
	rm -rf $(BUILD) $(SAN_BUILD)

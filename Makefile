# The two commands of the README, plus the developer targets (HACKING.md).
# make demo   installs dependencies, builds (Release) and runs the main job into out/demo/
# make test   installs dependencies, builds and runs the tests, then again under ASan+UBSan
# make bench  builds and runs the benchmarks

JOBS ?= $(shell nproc)
RFD := build/bin/rfd
DEMO := out/demo

.PHONY: all deps build build-asan test test-release test-asan bench demo clean

all: build

deps:
	@./scripts/install-deps.sh

build: deps
	cmake --preset release
	cmake --build build -j $(JOBS)

build-asan: deps
	cmake --preset asan
	cmake --build build-asan -j $(JOBS)

test: test-release test-asan

test-release: build
	ctest --preset release -j $(JOBS)

test-asan: build-asan
	ctest --preset asan -j $(JOBS)

bench: build
	./build/bin/rfd_bench --benchmark_counters_tabular=true

demo: build
	./scripts/demo.sh $(RFD) $(DEMO)

clean:
	rm -rf build build-asan build-debug out

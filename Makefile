# The two commands of the README, plus the developer targets (HACKING.md).
# make demo      installs dependencies, builds rfd (Release) and runs the maker's demo into out/demo/
# make test      installs dependencies, builds and runs the tests, then again under ASan+UBSan
# make studies   the research reproductions (sampling, implicit relighting, upsampling) into out/studies/
# make bench     builds and runs the benchmarks
# make docs      regenerates docs/options.md from the program's options (ctest doc_options checks it)
# make test-all  every test in both builds, the ones `make test` leaves to the Release build too

JOBS ?= $(shell nproc)
RFD := build/bin/rfd

.PHONY: all deps configure build build-tests build-asan build-asan-all test test-release test-asan test-all \
        bench demo docs studies clean

all: build

# Each stage of `make test` says when it starts, so a CI log shows where the time goes.
STAGE = @echo "== $$(date +%T) $@"

deps:
	$(STAGE)
	@./scripts/install-deps.sh

configure: deps
	cmake --preset release

# Only the program (and the modules it loads): what the demo and the studies run.
build: configure
	cmake --build build -j $(JOBS) --target rfd

build-tests: configure
	$(STAGE)
	cmake --build build -j $(JOBS) --target rfd rfd_tests

build-asan: deps
	$(STAGE)
	cmake --preset asan
	cmake --build build-asan -j $(JOBS) --target rfd rfd_tests

# The fuzz driver too: its bounded runs (label fuzz) are part of test-all.
build-asan-all: build-asan
	cmake --build build-asan -j $(JOBS) --target rfd_fuzz

test: test-release test-asan

test-release: build-tests
	$(STAGE)
	ctest --preset release -j $(JOBS)

test-asan: build-asan
	$(STAGE)
	ctest --preset asan -j $(JOBS)
	$(STAGE) done

test-all: build-tests build-asan-all
	ctest --preset release -j $(JOBS)
	ctest --preset asan-all -j $(JOBS)

bench: configure
	cmake --build build -j $(JOBS) --target rfd_bench
	./build/bin/rfd_bench --benchmark_counters_tabular=true

docs: build
	$(RFD) options-doc > docs/options.md

demo: build
	./scripts/demo.sh $(RFD) out/demo

studies: build
	./scripts/studies.sh $(RFD) out/studies

clean:
	rm -rf build build-asan build-debug build-fuzz out

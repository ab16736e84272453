# overtake: the two commands of the README, and a few more for development.
#   make demo   install what the binary needs and is missing (scripts/install-deps.sh --demo), build
#               the binary (Release), drive the built-in track, print the scorecard and write the
#               drive as a page to open in a browser
#   make check  install everything that is missing, build, run every test (also under ASan + UBSan),
#               fuzz every parser briefly
#   make fuzz   the libFuzzer harnesses (fuzz/) for FUZZ_SECONDS each; findings in build/fuzz/findings
#   make format-check  the C++ sources against .clang-format (make format fixes them)
#   make tidy   clang-tidy (.clang-tidy) over src/, with the release build's compile commands
.PHONY: all deps deps-demo build demo check test test-asan fuzz-build fuzz-smoke fuzz bench format \
        format-check tidy clean

FUZZ_SECONDS ?= 600

all: build

# Everything: the build, the tests, the sanitizer and fuzz builds, format, clang-tidy, the cluster
# and browser tests (scripts/install-deps.sh --help lists the packages).
deps:
	@scripts/install-deps.sh

# What the demo needs: configuring the demo preset, the binary with its web pages and the Python
# module, the drive, numpy for the README's Python lines.
deps-demo:
	@scripts/install-deps.sh --demo

build: deps
	@cmake --preset release >/dev/null
	@cmake --build --preset release

# Only the binary and the Python module are built (not the tests and benchmarks; the demo
# preset shares build/release with the release one): the drive, its scorecard, and the drive
# as one self-contained page to open in a browser.
demo: deps-demo
	@cmake --preset demo >/dev/null
	@cmake --build --preset demo --target overtake overtake_py
	@mkdir -p build/demo
	./build/release/overtake drive --minutes 10 --record build/demo/drive.otr
	@./build/release/overtake view build/demo/drive.otr --html build/demo/drive.html --quiet
	@echo
	@echo "Watch the drive: open build/demo/drive.html in a browser (one self-contained file),"
	@echo "or serve it with: ./build/release/overtake view build/demo/drive.otr"

test: build
	ctest --preset release

test-asan: deps
	@cmake --preset asan >/dev/null
	@cmake --build --preset asan
	ctest --preset asan

# The harnesses over their seeds and ~10 s of fuzzing each (about a minute in all).
fuzz-smoke: fuzz-build
	@scripts/fuzz.sh smoke

fuzz: fuzz-build
	@FUZZ_SECONDS=$(FUZZ_SECONDS) scripts/fuzz.sh long

fuzz-build: deps
	@cmake --preset fuzz >/dev/null
	@cmake --build --preset fuzz

# The cheap checks first: the format (seconds), clang-tidy (about a minute on 2 cores).
check: format-check tidy test test-asan fuzz-smoke

bench: build
	./build/release/overtake_bench

format: deps
	@scripts/format.sh fix

format-check: deps
	@scripts/format.sh check

tidy: deps
	@cmake --preset release >/dev/null
	@scripts/tidy.sh

clean:
	rm -rf build

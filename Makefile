# overtake: the two commands of the README, and a few more for development.
#   make demo   install what is missing, build (Release), drive the built-in track, print the scorecard
#   make check  install what is missing, build, run every test (also under ASan + UBSan)
.PHONY: all deps build demo check test test-asan bench format clean

all: build

deps:
	@scripts/install-deps.sh

build: deps
	@cmake --preset release >/dev/null
	@cmake --build --preset release

demo: build
	./build/release/overtake drive --minutes 10

test: build
	ctest --preset release

test-asan: deps
	@cmake --preset asan >/dev/null
	@cmake --build --preset asan
	ctest --preset asan

check: test test-asan

bench: build
	./build/release/overtake_bench

format:
	@find src tests bench -name '*.cpp' -o -name '*.hpp' | xargs clang-format -i

clean:
	rm -rf build

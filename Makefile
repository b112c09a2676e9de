# The two commands of the README: `make demo` and `make test`. Both run scripts/setup first.
# In CI (CI=true) warnings are errors.
.PHONY: setup build build-asan demo test test-release test-asan bench clean

ifeq ($(CI),true)
export BUILTSCENE_WERROR := ON
else
export BUILTSCENE_WERROR ?= OFF
endif

setup:
	@bash scripts/setup

build: setup
	cmake --preset release >/dev/null
	cmake --build --preset release

build-asan: setup
	cmake --preset asan >/dev/null
	cmake --build --preset asan

demo: build
	./build/release/apps/builtscene/builtscene demo --out demo-out
	@echo "Report: $(CURDIR)/demo-out/index.html"

# Every test runs once: the end-to-end (slow) tests on the release tree, the unit tests under
# ASan+UBSan (`ctest --preset release` still runs all of them on the release tree).
test-release: build
	ctest --preset release-slow

test-asan: build-asan
	ctest --preset asan

test: test-release test-asan

bench: build
	bash bench/run_all.sh

clean:
	rm -rf build demo-out

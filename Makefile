# linemap: the two commands are `make demo` and `make test` (the whole suite, what CI runs); `make check`
# is the fast tier (the unit tests alone); everything else is a helper.
SHELL := /bin/bash
export PATH := /usr/bin:/bin:/usr/sbin:/sbin:$(PATH)
BUILD_DIR ?= .build
export BUILD_DIR
# SANITIZE=1: ASan+UBSan build and tests in .build-sanitize (see scripts/build.sh).
SANITIZE ?= 0
export SANITIZE

.PHONY: all setup build test check demo format clean fuzz
all: build

setup:
	@bash scripts/setup.sh

build: setup
	@bash scripts/build.sh

test:
	@LINEMAP_QUIET=1 bash scripts/setup.sh
	@bash scripts/test.sh

check:
	@LINEMAP_QUIET=1 bash scripts/setup.sh
	@bash scripts/check.sh

demo:
	@LINEMAP_QUIET=1 bash scripts/setup.sh
	@bash scripts/demo.sh

# libFuzzer targets, FUZZ_SECONDS (default 60) each; see scripts/fuzz.sh.
fuzz: setup
	@bash scripts/fuzz.sh run

format:
	@git ls-files '*.cpp' '*.hpp' | xargs clang-format -i

clean:
	rm -rf $(BUILD_DIR) output CMakeLists.txt
